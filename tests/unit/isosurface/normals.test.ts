// Vertex normals are computed once per surface by the vertex pass (not per
// frame by the renderer): the GPU's octahedral normals equal a CPU
// computation of the same rule (central differences at both ends of the
// vertex's grid edge, interpolated; one-sided where a neighbour is outside
// the volume or in a block not cached) on the decoded volume, at every
// vertex, across several vertex shards and after growth.
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { NONE } from '../../../src/isosurface/layout.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { soupNormals } from '../../../src/render/testing/cpu-surface.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField } from './helpers.ts';
import { readCacheState, readNormals, readVertices } from '../../helpers/isosurface-readback.ts';

/** vertex_format.wgsl decode_vertex_normal, in TS (unit vector, or zero for 0). */
function decodeNormal(packed: number): [number, number, number] {
  if (packed === 0) return [0, 0, 0];
  const o = [((packed & 0xffff) - 1) / 65534, ((packed >>> 16) - 1) / 65534].map((q) => q * 2 - 1);
  let n = [o[0], o[1], 1 - Math.abs(o[0]) - Math.abs(o[1])];
  if (n[2] < 0) n = [(1 - Math.abs(n[1])) * (n[0] >= 0 ? 1 : -1), (1 - Math.abs(n[0])) * (n[1] >= 0 ? 1 : -1), n[2]];
  const l = Math.hypot(n[0], n[1], n[2]);
  return [n[0] / l, n[1] / l, n[2] / l];
}

describe('vertex normals', () => {
  for (const [kind, dims, seed] of [
    ['blobs', [29, 23, 19], 3],
    ['noise', [13, 11, 9], 8],
  ] as const) {
    gpuTest(`${kind} ${dims.join('x')}: GPU normals = CPU gradient rule at every vertex`, async ({ gpu }) => {
      const { device } = gpu;
      const d = [...dims] as Dims;
      const stream = await compressVolume(device, makeField(d, seed, kind), d, 10);
      const decoded = await decodeVolume(device, stream);
      // small cache and vertex buffers (growth), several shards
      const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 2, initialVertexCapacity: 30, maxVertexBindingBytes: 8 * 999 });
      const [lo, hi] = iso.info.valueRange;
      for (const f of [0.35, 0.6]) {
        const t = Math.fround(lo + f * (hi - lo));
        const stats = await iso.compute(t);
        const packed = await readVertices(iso);
        const normals = await readNormals(iso);
        expect(normals.length).toBe(stats.indices);
        const positions = decodeVertices(packed, normals.length, 2);
        const { blockToSlot } = await readCacheState(iso);
        const readable = (b: number) => blockToSlot[b] !== NONE;
        const want = soupNormals(decoded, d, positions, readable);
        // The GPU interpolates at the exact edge parameter, the CPU at the
        // quantized position (within half a step, 0.5/65535 voxel, along the
        // edge, plus float32 rounding of the decoded coordinate): the CPU
        // normals at both ends of that interval bound the difference.
        const shifted = (delta: number) => {
          const p = positions.slice();
          for (let i = 0; i < p.length; i += 3) {
            const dist = [0, 1, 2].map((a) => Math.abs(p[i + a] - Math.round(p[i + a])));
            const axis = dist[1] > dist[0] && dist[1] >= dist[2] ? 1 : dist[2] > dist[0] && dist[2] > dist[1] ? 2 : 0;
            p[i + axis] += delta;
          }
          return soupNormals(decoded, d, p, readable);
        };
        const step = 2.01 / 65535;
        const below = shifted(-step);
        const above = shifted(step);
        const angle = (a: Float32Array, b: Float32Array, i: number) => {
          const la = Math.hypot(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
          const lb = Math.hypot(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
          return Math.acos(Math.min(1, (a[3 * i] * b[3 * i] + a[3 * i + 1] * b[3 * i + 1] + a[3 * i + 2] * b[3 * i + 2]) / (la * lb || 1)));
        };
        let worst = 0;
        let zeros = 0;
        for (let i = 0; i < normals.length; i++) {
          const w = [want[3 * i], want[3 * i + 1], want[3 * i + 2]];
          const wl = Math.hypot(w[0], w[1], w[2]);
          const g = decodeNormal(normals[i]);
          if (wl < 1e-3) {
            // no gradient to speak of: either encoding is fine, but a zero on the GPU needs one here
            if (normals[i] === 0) zeros++;
            continue;
          }
          expect(normals[i], `vertex ${i}: no normal on the GPU, CPU gradient length ${wl}`).not.toBe(0);
          const cos = (g[0] * w[0] + g[1] * w[1] + g[2] * w[2]) / wl;
          const slack = Math.max(angle(below, want, i), angle(above, want, i));
          worst = Math.max(worst, Math.acos(Math.min(1, cos)) - slack);
        }
        // beyond the quantization slack: the 16-bit octahedral encoding (< 1e-4 rad) and float rounding
        expect(worst, `iso ${t}: largest angle between GPU and CPU normals beyond the position quantization (rad)`).toBeLessThan(0.002);
        expect(zeros).toBeLessThanOrEqual(normals.length * 0.01);
      }
      iso.destroy();
      stream.destroy();
    });
  }
});
