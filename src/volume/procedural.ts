// The built-in default volume, generated in the page (no download), seeded so
// every run shows the same data. It holds both kinds of isosurface the paper
// studies, in one scalar field with values in [0, 1], y up:
//   - a turbulent sheet: the interface of a mixing layer whose height is a
//     fractal noise of (x, z), like the Richtmyer-Meshkov data;
//   - nested shells: concentric spherical shells above the sheet, opened on
//     one side so inner shells show through, like a CT scan's skin and bone.
// value = max(sheet, shells), so a surface of the union shows both at once.

import { DEFAULT_VIEW_DIRECTION } from '../core/view.ts';
import type { Dims } from '../core/naming.ts';
import { mulberry32 } from '../util/random.ts';

export interface ProceduralVolume {
  name: string;
  dims: Dims;
  data: Float32Array;
  /** An isovalue that shows both structures. */
  defaultIsovalue: number;
}

/** 2D value noise on a seeded lattice, smooth (quintic) interpolation. */
class ValueNoise2D {
  private readonly table: Float32Array;
  private static readonly N = 256;

  constructor(random: () => number) {
    this.table = new Float32Array(ValueNoise2D.N * ValueNoise2D.N);
    for (let i = 0; i < this.table.length; i++) this.table[i] = random() * 2 - 1;
  }

  private at(i: number, j: number): number {
    const n = ValueNoise2D.N;
    return this.table[(((j % n) + n) % n) * n + (((i % n) + n) % n)];
  }

  sample(x: number, y: number): number {
    const i = Math.floor(x);
    const j = Math.floor(y);
    const fx = x - i;
    const fy = y - j;
    const sx = fx * fx * fx * (fx * (fx * 6 - 15) + 10);
    const sy = fy * fy * fy * (fy * (fy * 6 - 15) + 10);
    const a = this.at(i, j) + (this.at(i + 1, j) - this.at(i, j)) * sx;
    const b = this.at(i, j + 1) + (this.at(i + 1, j + 1) - this.at(i, j + 1)) * sx;
    return a + (b - a) * sy;
  }

  /** Fractal sum of octaves with a domain warp, for a turbulent look. */
  fbm(x: number, y: number, octaves: number): number {
    let sum = 0;
    let amp = 0.5;
    let freq = 1;
    for (let o = 0; o < octaves; o++) {
      const wx = this.sample(x * freq + 17.3, y * freq - 4.1) * 0.6;
      sum += amp * this.sample(x * freq + wx, y * freq - wx);
      amp *= 0.55;
      freq *= 2.03;
    }
    return sum;
  }
}

function smoothstep(e0: number, e1: number, x: number): number {
  const t = Math.min(1, Math.max(0, (x - e0) / (e1 - e0)));
  return t * t * (3 - 2 * t);
}

export function generateDefaultVolume(dims: Dims = [128, 128, 128], seed = 20201025): ProceduralVolume {
  const [nx, ny, nz] = dims;
  const random = mulberry32(seed);
  const noise = new ValueNoise2D(random);
  const data = new Float32Array(nx * ny * nz);

  // Y is up (as in ParaView's default view and the page's): the sheet's
  // height (in units of y in [0, 1]) per (x, z) column, computed once.
  const height = new Float32Array(nx * nz);
  for (let k = 0; k < nz; k++) {
    for (let i = 0; i < nx; i++) {
      const u = (i / nx) * 4.5;
      const v = (k / nz) * 4.5;
      height[k * nx + i] = 0.3 + 0.13 * noise.fbm(u, v, 4);
    }
  }
  const layerWidth = 0.035;
  // Shells: centre above the sheet, 4 shells, opened on the side the default
  // view sees at an angle (it looks from DEFAULT_VIEW_DIRECTION; the window
  // faces 35 degrees to its right, so the cut shows the shells' thickness).
  const cx = 0.5,
    cy = 0.68,
    cz = 0.5,
    radius = 0.28,
    shells = 4;
  const [wx, wy, wz] = [DEFAULT_VIEW_DIRECTION[0] + 0.55, DEFAULT_VIEW_DIRECTION[1] - 0.1, DEFAULT_VIEW_DIRECTION[2] - 0.5];
  const wl = Math.hypot(wx, wy, wz);
  for (let k = 0; k < nz; k++) {
    const z = (k + 0.5) / nz;
    for (let j = 0; j < ny; j++) {
      const y = (j + 0.5) / ny;
      for (let i = 0; i < nx; i++) {
        const x = (i + 0.5) / nx;
        const sheet = 0.5 - 0.5 * Math.tanh((y - height[k * nx + i]) / layerWidth);
        const dx = x - cx,
          dy = y - cy,
          dz = z - cz;
        const d = Math.sqrt(dx * dx + dy * dy + dz * dz);
        const r = d / radius;
        let shell = 0;
        if (r < 1.15) {
          const wave = Math.cos(Math.PI * 2 * shells * r);
          // A window where the direction from the centre points at the camera.
          const dir = d > 1e-9 ? (dx * wx + dy * wy + dz * wz) / (d * wl) : 0;
          const window = 1 - smoothstep(0.5, 0.75, dir);
          shell = (0.5 + 0.45 * wave) * window * (1 - smoothstep(0.95, 1.1, r));
        }
        data[(k * ny + j) * nx + i] = Math.max(sheet, shell);
      }
    }
  }
  return { name: 'default (shells + turbulent sheet)', dims, data, defaultIsovalue: 0.5 };
}
