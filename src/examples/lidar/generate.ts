// A synthetic airborne LIDAR survey, generated in the page to show that
// tens of millions of points stay interactive: rolling terrain with lakes,
// roads, buildings and trees, with RGB, intensity and ASPRS classes like a
// real classified tile. Deterministic for a given seed. Coordinates are in
// metres, relative to the tile's centre (like the loader's positions).
import type { LasChunk } from '../../loaders/las.ts';
import { mulberry32 } from '../../util/random.ts';

export const GENERATED_EXTENT = 2000;

// Value noise on an integer lattice with smooth interpolation.
function hash2(ix: number, iy: number): number {
  let h = Math.imul(ix, 374761393) ^ Math.imul(iy, 668265263);
  h = Math.imul(h ^ (h >>> 13), 1274126177);
  return ((h ^ (h >>> 16)) >>> 0) / 4294967296;
}

function noise(x: number, y: number): number {
  const ix = Math.floor(x);
  const iy = Math.floor(y);
  const fx = x - ix;
  const fy = y - iy;
  const ux = fx * fx * (3 - 2 * fx);
  const uy = fy * fy * (3 - 2 * fy);
  const a = hash2(ix, iy);
  const b = hash2(ix + 1, iy);
  const c = hash2(ix, iy + 1);
  const d = hash2(ix + 1, iy + 1);
  return a + (b - a) * ux + (c - a) * uy + (a - b - c + d) * ux * uy;
}

function fbm(x: number, y: number, octaves: number): number {
  let sum = 0;
  let amp = 0.5;
  let f = 1;
  for (let o = 0; o < octaves; o++) {
    sum += amp * noise(x * f, y * f);
    f *= 2.03;
    amp *= 0.5;
  }
  return sum;
}

const WATER_LEVEL = 8;

/** Ground height (m) at (x, y). */
function ground(x: number, y: number): number {
  const hills = fbm(x / 520 + 11.3, y / 520 - 4.1, 5) * 95 - 20;
  // A river valley winding across the tile.
  const riverY = 260 * Math.sin(x / 430) + 90 * Math.sin(x / 170 + 1.3);
  const d = Math.abs(y - riverY);
  const valley = Math.min(1, d / 160);
  return hills * (0.25 + 0.75 * valley * valley) + 2;
}

interface Building {
  x: number;
  y: number;
  hw: number;
  hd: number;
  angle: number;
  base: number;
  height: number;
  roof: [number, number, number];
  /** Gabled roof ridge along the local x axis. */
  gable: boolean;
}

interface Tree {
  x: number;
  y: number;
  r: number;
  base: number;
  height: number;
  tint: number;
}

const CELL = 40;

class Scene {
  readonly buildings: Building[] = [];
  readonly trees: Tree[] = [];
  private readonly grid = new Map<number, { b: Building[]; t: Tree[] }>();

  constructor(seed: number) {
    const rnd = mulberry32(seed);
    const half = GENERATED_EXTENT / 2;
    const roofs: [number, number, number][] = [
      [170, 84, 62],
      [140, 70, 55],
      [120, 120, 125],
      [90, 92, 98],
      [185, 160, 130],
    ];
    for (let i = 0; i < 900; i++) {
      // Town in one quadrant, scattered farms elsewhere.
      const town = i < 650;
      const x = town ? 350 + (rnd() - 0.5) * 700 : (rnd() - 0.5) * GENERATED_EXTENT;
      const y = town ? -420 + (rnd() - 0.5) * 600 : (rnd() - 0.5) * GENERATED_EXTENT;
      const base = ground(x, y);
      if (base < WATER_LEVEL + 2 || Math.abs(x) > half - 40 || Math.abs(y) > half - 40) continue;
      const hw = 5 + rnd() * (town ? 14 : 9);
      const hd = 5 + rnd() * 10;
      const b: Building = {
        x,
        y,
        hw,
        hd,
        angle: town ? Math.round(rnd() * 2) * 0.05 + 0.35 : rnd() * Math.PI,
        base,
        height: 5 + rnd() * (town ? (rnd() < 0.1 ? 40 : 14) : 6),
        roof: roofs[Math.floor(rnd() * roofs.length)],
        gable: rnd() < 0.6,
      };
      if (this.buildings.some((o) => Math.hypot(o.x - b.x, o.y - b.y) < Math.max(o.hw, o.hd) + Math.max(b.hw, b.hd) + 3)) continue;
      this.buildings.push(b);
      this.insert(b.x, b.y, Math.hypot(b.hw, b.hd), (c) => c.b.push(b));
    }
    for (let i = 0; i < 16000; i++) {
      // Forest patches from low-frequency noise; fewer trees in town.
      const x = (rnd() - 0.5) * GENERATED_EXTENT;
      const y = (rnd() - 0.5) * GENERATED_EXTENT;
      const forest = fbm(x / 300 + 40, y / 300 + 7, 3);
      if (forest < 0.52 && rnd() > 0.04) continue;
      const base = ground(x, y);
      if (base < WATER_LEVEL + 1) continue;
      const t: Tree = { x, y, r: 2.5 + rnd() * 5, base, height: 8 + rnd() * 18, tint: rnd() };
      if (this.near(x, y).b.some((b) => this.inBuilding(b, x, y, t.r + 2))) continue;
      this.trees.push(t);
      this.insert(x, y, t.r, (c) => c.t.push(t));
    }
  }

  private key(cx: number, cy: number): number {
    return (cx + 1000) * 4096 + (cy + 1000);
  }

  private insert(x: number, y: number, r: number, add: (c: { b: Building[]; t: Tree[] }) => void): void {
    for (let cx = Math.floor((x - r) / CELL); cx <= Math.floor((x + r) / CELL); cx++)
      for (let cy = Math.floor((y - r) / CELL); cy <= Math.floor((y + r) / CELL); cy++) {
        const k = this.key(cx, cy);
        let c = this.grid.get(k);
        if (!c) this.grid.set(k, (c = { b: [], t: [] }));
        add(c);
      }
  }

  private static readonly EMPTY = { b: [] as Building[], t: [] as Tree[] };

  near(x: number, y: number): { b: Building[]; t: Tree[] } {
    return this.grid.get(this.key(Math.floor(x / CELL), Math.floor(y / CELL))) ?? Scene.EMPTY;
  }

  inBuilding(b: Building, x: number, y: number, margin = 0): boolean {
    const c = Math.cos(b.angle);
    const s = Math.sin(b.angle);
    const dx = x - b.x;
    const dy = y - b.y;
    return Math.abs(dx * c + dy * s) < b.hw + margin && Math.abs(-dx * s + dy * c) < b.hd + margin;
  }
}

export interface GenerateOptions {
  seed?: number;
  chunkSize?: number;
  /** Called with each chunk; `rgb` holds 8-bit values in uint16 like many LAS files. */
  onChunk: (chunk: LasChunk) => void;
  onProgress?: (done: number, total: number) => void;
  /** Yield to the event loop between chunks (the page repaints its progress bar). */
  yieldBetweenChunks?: boolean;
  /** Stops generating (e.g. a file was dropped meanwhile). */
  cancelled?: () => boolean;
}

/** Generates `count` points in chunks. Resolves when all chunks were delivered. */
export async function generatePointCloud(
  count: number,
  options: GenerateOptions,
): Promise<{ bounds: { min: [number, number, number]; max: [number, number, number] } }> {
  const scene = new Scene(options.seed ?? 7);
  const rnd = mulberry32((options.seed ?? 7) * 7919 + 1);
  const chunkSize = options.chunkSize ?? 1 << 18;
  const half = GENERATED_EXTENT / 2;
  const min: [number, number, number] = [Infinity, Infinity, Infinity];
  const max: [number, number, number] = [-Infinity, -Infinity, -Infinity];
  for (let start = 0; start < count; start += chunkSize) {
    const n = Math.min(chunkSize, count - start);
    const positions = new Float32Array(n * 3);
    const rgb = new Uint16Array(n * 3);
    const intensity = new Uint16Array(n);
    const classification = new Uint8Array(n);
    for (let i = 0; i < n; i++) {
      const x = (rnd() - 0.5) * GENERATED_EXTENT;
      const y = (rnd() - 0.5) * GENERATED_EXTENT;
      const g = ground(x, y);
      let z = g;
      let cls = 2;
      let r = 0;
      let gr = 0;
      let b = 0;
      let inten = 0;
      const cell = scene.near(x, y);
      let hit = false;
      for (const bd of cell.b) {
        if (!scene.inBuilding(bd, x, y)) continue;
        const c = Math.cos(bd.angle);
        const s = Math.sin(bd.angle);
        const ly = -(x - bd.x) * s + (y - bd.y) * c;
        // Gabled roofs slope down from the ridge.
        const slope = bd.gable ? (1 - Math.abs(ly) / bd.hd) * Math.min(bd.hd, 8) * 0.6 : 0;
        z = bd.base + bd.height + slope;
        cls = 6;
        const shade = bd.gable ? (ly > 0 ? 1.0 : 0.82) : 0.95;
        r = bd.roof[0] * shade;
        gr = bd.roof[1] * shade;
        b = bd.roof[2] * shade;
        inten = 2600 + rnd() * 1400;
        hit = true;
        break;
      }
      if (!hit) {
        for (const t of cell.t) {
          const d2 = ((x - t.x) ** 2 + (y - t.y) ** 2) / (t.r * t.r);
          if (d2 >= 1) continue;
          // Some pulses reach the ground through the crown.
          if (rnd() < 0.15) break;
          const crown = Math.sqrt(1 - d2);
          z = t.base + t.height * (0.55 + 0.45 * crown) + (rnd() - 0.5) * 0.8;
          cls = z - t.base > 6 ? 5 : z - t.base > 2 ? 4 : 3;
          const v = 0.75 + 0.5 * crown + (rnd() - 0.5) * 0.25;
          r = (38 + 30 * t.tint) * v;
          gr = (82 + 40 * (1 - t.tint)) * v;
          b = (34 + 12 * t.tint) * v;
          inten = 500 + rnd() * 900;
          hit = true;
          break;
        }
      }
      if (!hit) {
        if (g < WATER_LEVEL) {
          z = WATER_LEVEL + (rnd() - 0.5) * 0.1;
          cls = 9;
          const depth = Math.min(1, (WATER_LEVEL - g) / 12);
          r = 40 - 20 * depth;
          gr = 90 - 30 * depth;
          b = 130 - 10 * depth;
          inten = 60 + rnd() * 120;
        } else {
          // Roads: two gently curving bands.
          const road1 = Math.abs(x - 380 - 60 * Math.sin(y / 260));
          const road2 = Math.abs(y + 420 - 40 * Math.sin(x / 300));
          const t = fbm(x / 40, y / 40, 3);
          if (road1 < 5 || (road2 < 4 && x > -600)) {
            cls = 11;
            const v = 95 + t * 30;
            r = v;
            gr = v;
            b = v + 6;
            inten = 1100 + rnd() * 400;
          } else {
            const dry = Math.min(1, Math.max(0, (g - 20) / 60));
            const v = 0.8 + t * 0.45;
            r = (88 + 70 * dry) * v;
            gr = (122 + 20 * dry) * v;
            b = (58 + 30 * dry) * v;
            inten = 1400 + t * 1800 + rnd() * 300;
          }
          z += (rnd() - 0.5) * 0.15;
        }
      }
      positions[3 * i] = x;
      positions[3 * i + 1] = y;
      positions[3 * i + 2] = z;
      rgb[3 * i] = Math.max(0, Math.min(255, r));
      rgb[3 * i + 1] = Math.max(0, Math.min(255, gr));
      rgb[3 * i + 2] = Math.max(0, Math.min(255, b));
      intensity[i] = inten;
      classification[i] = cls;
      if (x < min[0]) min[0] = x;
      if (y < min[1]) min[1] = y;
      if (z < min[2]) min[2] = z;
      if (x > max[0]) max[0] = x;
      if (y > max[1]) max[1] = y;
      if (z > max[2]) max[2] = z;
    }
    options.onChunk({ start, count: n, positions, rgb, intensity, classification });
    options.onProgress?.(start + n, count);
    if (options.yieldBetweenChunks) await new Promise((r) => setTimeout(r, 0));
    if (options.cancelled?.()) break;
  }
  if (count === 0) return { bounds: { min: [-half, -half, 0], max: [half, half, 1] } };
  return { bounds: { min, max } };
}
