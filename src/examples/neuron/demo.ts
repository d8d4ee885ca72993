// A synthetic neuron for the page's first view: a traced morphology (soma,
// dendrites, an apical dendrite and an axon, as an SWC tree) and a
// fluorescence-like image stack of the same cell (the traced tubes blurred by
// a point-spread function, with background and noise), so the volume and the
// traces can be compared the way a neuroanatomist checks a reconstruction.
// Deterministic for a given seed.
import type { SwcTree } from '../../loaders/swc.ts';
import { mulberry32 } from '../../util/random.ts';

export interface DemoNeuron {
  tree: SwcTree;
  /** uint8, [z][y][x]. */
  volume: Uint8Array;
  dims: [number, number, number];
  /** Microns per voxel. */
  spacing: [number, number, number];
}

interface Sample {
  type: number;
  x: number;
  y: number;
  z: number;
  r: number;
  parent: number;
}

export function makeDemoNeuron(seed = 3): DemoNeuron {
  const rnd = mulberry32(seed);
  const gauss = () => Math.sqrt(-2 * Math.log(rnd() + 1e-12)) * Math.cos(2 * Math.PI * rnd());
  const dims: [number, number, number] = [192, 192, 48];
  const spacing: [number, number, number] = [1, 1, 2];
  const extent = dims.map((d, a) => d * spacing[a]);
  const centre = [extent[0] * 0.5, extent[1] * 0.55, extent[2] * 0.5];
  const samples: Sample[] = [];
  samples.push({ type: 1, x: centre[0], y: centre[1], z: centre[2], r: 7, parent: -1 });

  const grow = (type: number, dir: [number, number, number], r0: number, length: number, parent: number, depth: number) => {
    let [dx, dy, dz] = dir;
    let x = samples[parent].x + dx * samples[parent].r;
    let y = samples[parent].y + dy * samples[parent].r;
    let z = samples[parent].z + dz * samples[parent].r;
    let r = r0;
    let p = parent;
    const steps = Math.round(length / 3);
    for (let s = 0; s < steps; s++) {
      // Persistent random walk, flattened in z like a cell in a slice.
      dx += gauss() * 0.22;
      dy += gauss() * 0.22;
      dz += gauss() * 0.08 - dz * 0.15;
      const n = Math.hypot(dx, dy, dz);
      dx /= n;
      dy /= n;
      dz /= n;
      x += dx * 3;
      y += dy * 3;
      z += dz * 3;
      if (x < 4 || y < 4 || z < 4 || x > extent[0] - 4 || y > extent[1] - 4 || z > extent[2] - 4) break;
      r = Math.max(0.45, r * 0.99);
      samples.push({ type, x, y, z, r, parent: p });
      p = samples.length - 1;
      if (depth < 3 && s > 4 && rnd() < 0.07) {
        const a = (rnd() < 0.5 ? 1 : -1) * (0.5 + rnd() * 0.5);
        const c = Math.cos(a);
        const sn = Math.sin(a);
        grow(type, [dx * c - dy * sn, dx * sn + dy * c, dz], r * 0.8, length * (0.35 + rnd() * 0.3), p, depth + 1);
      }
    }
  };
  const dendrites = 5;
  for (let i = 0; i < dendrites; i++) {
    const a = (i / dendrites) * Math.PI * 2 + rnd() * 0.5;
    grow(3, [Math.cos(a), Math.sin(a) * 0.8 + 0.2, (rnd() - 0.5) * 0.3], 1.6, 100 + rnd() * 50, 0, 0);
  }
  grow(4, [0.05, -1, 0.05], 2.2, 150, 0, 1); // apical dendrite, towards the top of the image
  grow(2, [0.2, 1, -0.1], 0.9, 220, 0, 2); // axon

  // The image: the traced tubes blurred by a PSF (wider in z), plus background and noise.
  const [nx, ny, nz] = dims;
  const field = new Float32Array(nx * ny * nz);
  for (let i = 1; i < samples.length; i++) {
    const a = samples[i];
    const b = samples[a.parent];
    const bright = a.type === 1 ? 1 : a.type === 2 ? 0.55 : 0.85;
    const reach = Math.max(a.r, b.r) + 3;
    const lo = [Math.min(a.x, b.x) - reach, Math.min(a.y, b.y) - reach, Math.min(a.z, b.z) - reach * 2];
    const hi = [Math.max(a.x, b.x) + reach, Math.max(a.y, b.y) + reach, Math.max(a.z, b.z) + reach * 2];
    const abx = b.x - a.x;
    const aby = b.y - a.y;
    const abz = b.z - a.z;
    const len2 = abx * abx + aby * aby + abz * abz || 1;
    for (let k = Math.max(0, Math.floor(lo[2] / spacing[2])); k <= Math.min(nz - 1, Math.ceil(hi[2] / spacing[2])); k++)
      for (let j = Math.max(0, Math.floor(lo[1])); j <= Math.min(ny - 1, Math.ceil(hi[1])); j++)
        for (let ii = Math.max(0, Math.floor(lo[0])); ii <= Math.min(nx - 1, Math.ceil(hi[0])); ii++) {
          const px = ii * spacing[0];
          const py = j * spacing[1];
          const pz = k * spacing[2];
          const t = Math.min(1, Math.max(0, ((px - a.x) * abx + (py - a.y) * aby + (pz - a.z) * abz) / len2));
          const r = a.r + (b.r - a.r) * t;
          const dx = px - (a.x + abx * t);
          const dy = py - (a.y + aby * t);
          const dz = (pz - (a.z + abz * t)) / 1.8;
          const d = Math.sqrt(dx * dx + dy * dy + dz * dz);
          const v = bright * Math.exp(-(Math.max(0, d - r * 0.6) ** 2) / (2 * (0.8 + r * 0.35) ** 2));
          const idx = (k * ny + j) * nx + ii;
          if (v > field[idx]) field[idx] = v;
        }
  }
  const volume = new Uint8Array(nx * ny * nz);
  for (let i = 0; i < volume.length; i++) {
    const noise = 0.05 + 0.03 * gauss();
    volume[i] = Math.max(0, Math.min(255, Math.round((field[i] * 0.9 + noise) * 235)));
  }

  const n = samples.length;
  const tree: SwcTree = {
    fileName: 'demo-neuron.swc',
    count: n,
    ids: Int32Array.from(samples, (_, i) => i + 1),
    types: Int32Array.from(samples, (s) => s.type),
    positions: Float64Array.from(samples.flatMap((s) => [s.x, s.y, s.z])),
    radii: Float64Array.from(samples, (s) => s.r),
    parentIds: Int32Array.from(samples, (s) => (s.parent < 0 ? -1 : s.parent + 1)),
    parentIndex: Int32Array.from(samples, (s) => s.parent),
    comments: ['synthetic neuron generated in the page'],
  };
  return { tree, volume, dims, spacing };
}
