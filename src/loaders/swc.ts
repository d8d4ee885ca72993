// SWC neuron morphologies: one sample per line, `id type x y z radius parent`,
// `#` comments. Real files use the standard type codes 0-7 (undefined, soma,
// axon, basal dendrite, apical dendrite, fork point, end point, custom) and
// any higher code for lab-specific labels; all are accepted.

export type Vec3 = [number, number, number];

export interface SwcTree {
  fileName: string;
  count: number;
  ids: Int32Array;
  types: Int32Array;
  /** x, y, z per sample (float64). */
  positions: Float64Array;
  radii: Float64Array;
  /** Parent id per sample; -1 for roots. */
  parentIds: Int32Array;
  /**
   * Index of the parent sample, or -1: roots, parent ids missing from the
   * file, self-parents and samples on a parent cycle (links not drawn).
   */
  parentIndex: Int32Array;
  /** The comment lines (without '#'). */
  comments: string[];
  /** What is wrong with the tree (checkSwcTree), in words; empty for a sound tree. */
  problems?: string[];
}

/** A line that is not an SWC sample; the message names the file and line. */
export class SwcError extends Error {
  constructor(
    readonly fileName: string,
    readonly line: number,
    readonly reason: string,
  ) {
    super(`${fileName}, line ${line}: ${reason}`);
    this.name = 'SwcError';
  }
}

export const SWC_TYPE_NAMES: Record<number, string> = {
  0: 'undefined',
  1: 'soma',
  2: 'axon',
  3: 'basal dendrite',
  4: 'apical dendrite',
  5: 'fork point',
  6: 'end point',
  7: 'custom',
};

export function swcTypeName(type: number): string {
  return SWC_TYPE_NAMES[type] ?? `custom ${type}`;
}

// Colours in the spirit of common neuron viewers (neuTube, Vaa3D): soma
// white, axon blue-ish, basal dendrite red, apical dendrite magenta, ...
const TYPE_COLORS: Record<number, Vec3> = {
  0: [0.75, 0.75, 0.75],
  1: [0.95, 0.95, 0.95],
  2: [0.3, 0.55, 1.0],
  3: [1.0, 0.32, 0.28],
  4: [0.95, 0.3, 0.95],
  5: [0.3, 0.9, 0.45],
  6: [1.0, 0.85, 0.25],
  7: [0.35, 0.9, 0.95],
};

/** Display colour (linear-ish RGB in 0..1) for a type code; codes above 7 get a stable hue. */
export function swcTypeColor(type: number): Vec3 {
  const known = TYPE_COLORS[type];
  if (known) return known;
  // Golden-angle hues keep neighbouring custom codes apart.
  const h = ((Math.abs(type) * 137.508) % 360) / 60;
  const x = 1 - Math.abs((h % 2) - 1);
  const [r, g, b] = h < 1 ? [1, x, 0] : h < 2 ? [x, 1, 0] : h < 3 ? [0, 1, x] : h < 4 ? [0, x, 1] : h < 5 ? [x, 0, 1] : [1, 0, x];
  return [0.35 + 0.6 * r, 0.35 + 0.6 * g, 0.35 + 0.6 * b];
}

function integer(text: string, what: string, fileName: string, line: number): number {
  const v = Number(text);
  // Some writers print ids as "12.0"; anything else non-integral is an error.
  if (!Number.isFinite(v) || !Number.isInteger(v)) throw new SwcError(fileName, line, `${what} "${text}" is not an integer`);
  if (v < -2147483648 || v > 2147483647) throw new SwcError(fileName, line, `${what} ${text} is out of range`);
  return v;
}

function real(text: string, what: string, fileName: string, line: number): number {
  const v = Number(text);
  if (!Number.isFinite(v)) throw new SwcError(fileName, line, `${what} "${text}" is not a number`);
  return v;
}

/** Parses SWC text. Throws SwcError (file and line) for malformed lines. */
export function parseSwc(text: string, fileName = 'swc'): SwcTree {
  const ids: number[] = [];
  const types: number[] = [];
  const pos: number[] = [];
  const radii: number[] = [];
  const parents: number[] = [];
  const comments: string[] = [];
  const lines = text.split(/\r\n|\r|\n/);
  for (let i = 0; i < lines.length; i++) {
    const line = lines[i].trim();
    if (line === '') continue;
    if (line.startsWith('#')) {
      comments.push(line.slice(1).trim());
      continue;
    }
    const v = line.split(/\s+/);
    if (v.length < 7) {
      throw new SwcError(fileName, i + 1, `expected 7 columns (id type x y z radius parent), found ${v.length}: "${line.slice(0, 80)}"`);
    }
    ids.push(integer(v[0], 'id', fileName, i + 1));
    types.push(integer(v[1], 'type', fileName, i + 1));
    pos.push(real(v[2], 'x', fileName, i + 1), real(v[3], 'y', fileName, i + 1), real(v[4], 'z', fileName, i + 1));
    radii.push(real(v[5], 'radius', fileName, i + 1));
    parents.push(integer(v[6], 'parent', fileName, i + 1));
  }
  if (ids.length === 0) throw new SwcError(fileName, lines.length, 'no samples (an SWC file has lines "id type x y z radius parent")');
  const index = new Map<number, number>();
  // With duplicate ids the last sample wins, as in a dict-based reader.
  for (let i = 0; i < ids.length; i++) index.set(ids[i], i);
  const parentIndex = new Int32Array(ids.length);
  for (let i = 0; i < ids.length; i++) parentIndex[i] = parents[i] === -1 ? -1 : (index.get(parents[i]) ?? -1);
  const tree: SwcTree = {
    fileName,
    count: ids.length,
    ids: Int32Array.from(ids),
    types: Int32Array.from(types),
    positions: Float64Array.from(pos),
    radii: Float64Array.from(radii),
    parentIds: Int32Array.from(parents),
    parentIndex,
    comments,
  };
  // Draw what is valid: links of self-parents and of samples on a cycle are dropped.
  const check = checkSwcTree(tree);
  tree.parentIndex = check.parentIndex;
  tree.problems = check.problems;
  return tree;
}

export interface SwcCheck {
  /** Samples whose parent is themselves. */
  selfParents: number;
  /** Samples on parent cycles, and the number of cycles. */
  cycleSamples: number;
  cycles: number;
  /** Samples whose parent id (not -1) is not in the file. */
  danglingParents: number;
  /** Samples with parent -1. */
  roots: number;
  duplicateIds: number;
  /** parentIndex with the links of self-parents and cycle samples removed (-1). */
  parentIndex: Int32Array;
  /** Segments (sample to parent) drawn. */
  drawnSegments: number;
  /** One sentence per kind of problem, with counts and the first ids. */
  problems: string[];
}

function firstIds(list: number[]): string {
  return list.slice(0, 5).join(', ') + (list.length > 5 ? ', …' : '');
}

/**
 * Checks that the samples form trees: every parent id is -1 or a sample of
 * the file, no sample is its own parent, no chain of parents loops, and
 * there is a root. Says what was found; the returned parentIndex keeps only
 * valid links (what the neuron page draws).
 */
export function checkSwcTree(t: SwcTree): SwcCheck {
  const n = t.count;
  const index = new Map<number, number>();
  for (let i = 0; i < n; i++) index.set(t.ids[i], i);
  const parent = new Int32Array(n);
  const self: number[] = [];
  const dangling: number[] = [];
  let roots = 0;
  for (let i = 0; i < n; i++) {
    const p = t.parentIds[i];
    if (p === -1) {
      parent[i] = -1;
      roots++;
    } else if (p === t.ids[i]) {
      parent[i] = -1;
      self.push(t.ids[i]);
    } else {
      const j = index.get(p);
      parent[i] = j ?? -1;
      if (j === undefined) dangling.push(t.ids[i]);
    }
  }
  // Cycles: follow parents from each unvisited sample; meeting the current walk again closes a cycle.
  const state = new Uint8Array(n); // 0 new, 1 on the current walk, 2 done
  const onCycle: number[] = [];
  let cycles = 0;
  const walk: number[] = [];
  for (let s = 0; s < n; s++) {
    if (state[s] !== 0) continue;
    walk.length = 0;
    let i = s;
    while (i >= 0 && state[i] === 0) {
      state[i] = 1;
      walk.push(i);
      i = parent[i];
    }
    if (i >= 0 && state[i] === 1) {
      cycles++;
      let k = i;
      do {
        onCycle.push(k);
        k = parent[k];
      } while (k !== i);
    }
    for (const w of walk) state[w] = 2;
  }
  for (const k of onCycle) parent[k] = -1;
  let drawn = 0;
  for (let i = 0; i < n; i++) if (parent[i] >= 0) drawn++;
  const problems: string[] = [];
  if (self.length)
    problems.push(`${self.length} sample${self.length > 1 ? 's are their' : ' is its'} own parent (id ${firstIds(self)}); not linked`);
  if (cycles) {
    problems.push(
      `${cycles} parent cycle${cycles > 1 ? 's' : ''} (${onCycle.length} samples, id ${firstIds(onCycle.map((k) => t.ids[k]))}); their links are not drawn`,
    );
  }
  if (dangling.length)
    problems.push(
      `${dangling.length} sample${dangling.length > 1 ? 's name' : ' names'} a parent that is not in the file (id ${firstIds(dangling)}); drawn unlinked`,
    );
  if (roots === 0) problems.push('no root (no sample has parent -1)');
  return {
    selfParents: self.length,
    cycleSamples: onCycle.length,
    cycles,
    danglingParents: dangling.length,
    roots,
    duplicateIds: n - index.size,
    parentIndex: parent,
    drawnSegments: drawn,
    problems,
  };
}

export interface SwcStats {
  sampleCount: number;
  rootCount: number;
  rootIds: number[];
  /** Samples whose parent id is not -1 and not in the file. */
  orphanParentCount: number;
  duplicateIds: number;
  typeCounts: Record<string, number>;
  bbox: { min: Vec3; max: Vec3 };
  bboxWithRadius: { min: Vec3; max: Vec3 };
  /** Sum of sample-to-parent distances (float64, file order). */
  totalCableLength: number;
  segmentCount: number;
  /** Samples with two or more children. */
  branchPoints: number;
  /** Samples with no children. */
  tips: number;
  radiusMinMax: [number, number];
}

export function swcStats(t: SwcTree): SwcStats {
  const idSet = new Set<number>();
  for (const id of t.ids) idSet.add(id);
  const roots: number[] = [];
  let orphans = 0;
  let cable = 0;
  let segments = 0;
  const typeCounts: Record<string, number> = {};
  const children = new Map<number, number>();
  const min: Vec3 = [Infinity, Infinity, Infinity];
  const max: Vec3 = [-Infinity, -Infinity, -Infinity];
  const rmin: Vec3 = [Infinity, Infinity, Infinity];
  const rmax: Vec3 = [-Infinity, -Infinity, -Infinity];
  let radMin = Infinity;
  let radMax = -Infinity;
  const p = t.positions;
  for (let i = 0; i < t.count; i++) {
    const parent = t.parentIds[i];
    if (parent === -1) roots.push(t.ids[i]);
    else if (!idSet.has(parent)) orphans++;
    const pi = t.parentIndex[i];
    if (pi >= 0) {
      cable += Math.sqrt((p[3 * i] - p[3 * pi]) ** 2 + (p[3 * i + 1] - p[3 * pi + 1]) ** 2 + (p[3 * i + 2] - p[3 * pi + 2]) ** 2);
      segments++;
    }
    typeCounts[String(t.types[i])] = (typeCounts[String(t.types[i])] ?? 0) + 1;
    children.set(parent, (children.get(parent) ?? 0) + 1);
    const r = t.radii[i];
    for (let a = 0; a < 3; a++) {
      const v = p[3 * i + a];
      min[a] = Math.min(min[a], v);
      max[a] = Math.max(max[a], v);
      rmin[a] = Math.min(rmin[a], v - r);
      rmax[a] = Math.max(rmax[a], v + r);
    }
    radMin = Math.min(radMin, r);
    radMax = Math.max(radMax, r);
  }
  let branchPoints = 0;
  for (const [id, n] of children) if (id !== -1 && n >= 2) branchPoints++;
  let tips = 0;
  for (const id of t.ids) if (!children.has(id)) tips++;
  return {
    sampleCount: t.count,
    rootCount: roots.length,
    rootIds: roots.slice(0, 10),
    orphanParentCount: orphans,
    duplicateIds: t.count - idSet.size,
    typeCounts,
    bbox: { min, max },
    bboxWithRadius: { min: rmin, max: rmax },
    totalCableLength: cable,
    segmentCount: segments,
    branchPoints,
    tips,
    radiusMinMax: [radMin, radMax],
  };
}
