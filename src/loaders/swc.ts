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
  /** Index of the parent sample, or -1 (root, or a parent id missing from the file). */
  parentIndex: Int32Array;
  /** The comment lines (without '#'). */
  comments: string[];
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
  return {
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
