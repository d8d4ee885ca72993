// GPU block marching cubes against the serial CPU marching cubes (same case
// table) on random volumes of awkward sizes, triangle for triangle: the GPU
// soup and the CPU soup of the same decoded data, quantized alike, must be
// equal as sets of triangles (winding included), each coordinate within one
// quantization step (soup-compare.ts); the dequantized GPU soup must also
// match the CPU soup within half a step plus rounding, where it is unambiguous.
// Sizes not multiples of 4, single-block volumes, volumes without cells, 2D/3D
// dispatch grids, several vertex shards and stream shards, growth from a
// one-slot cache and a one-vertex buffer; groups of 1, 3 and the default
// number of blocks in the active-block selection on every case.
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceOptions } from '../../../src/isosurface/types.ts';
import { meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from '../mc/reference.ts';
import { compressVolume, decodeVolume, drawnSoup, makeField, testKernelOptions, VERTEX_TOLERANCE, type FieldKind } from './helpers.ts';
import { compareBlockSoups, cpuTriangles, crossedEdges, gpuTriangles } from './soup-compare.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';

interface Case {
  dims: Dims;
  kind: FieldKind;
  options?: IsosurfaceOptions;
  maxShardBytes?: number;
}

const CASES: Case[] = [
  { dims: [4, 4, 4], kind: 'noise' }, // one block
  { dims: [3, 3, 3], kind: 'noise' }, // one partial block
  { dims: [2, 2, 2], kind: 'noise' }, // one cell
  { dims: [1, 6, 5], kind: 'noise' }, // no cells at all
  { dims: [5, 5, 5], kind: 'noise' }, // 8 blocks, 7 of them partial
  { dims: [9, 13, 6], kind: 'noise', options: { maxWorkgroupsPerDimension: 3 } }, // 2D/3D grids
  { dims: [17, 3, 11], kind: 'blobs', options: { initialCacheSlots: 1, initialVertexCapacity: 1 } }, // growth
  { dims: [16, 16, 16], kind: 'blobs' },
  { dims: [33, 18, 7], kind: 'noise', options: { maxVertexBindingBytes: 8 * 1000 } }, // several vertex shards
  { dims: [26, 30, 21], kind: 'blobs', options: { maxVertexBindingBytes: 8 * 777, maxWorkgroupsPerDimension: 5 }, maxShardBytes: 16384 },
];

/** Four isovalues through one Isosurface: every surface equal to the serial one. */
async function checkSurfaces(iso: Isosurface, decoded: Float32Array, c: Case, label: string): Promise<void> {
  const random = rng(c.dims[0] + 1000 * c.dims[2]);
  const [lo, hi] = iso.info.valueRange;
  let shardsUsed = 0;
  for (let k = 0; k < 4; k++) {
    const t = Math.fround(lo + (hi - lo) * (0.1 + 0.8 * random()));
    const stats = await iso.compute(t);
    const packed = await readVertices(iso);
    const cpu = marchingCubes(decoded, c.dims, t);
    expect(stats.triangles, `${label} iso ${t}`).toBe(cpu.triangleCount);
    expect(stats.indices).toBe(packed.length / 2);
    expect(stats.vertices).toBe(crossedEdges(decoded, c.dims, t));
    const cmp = compareBlockSoups(gpuTriangles(packed, c.dims), cpuTriangles(decoded, c.dims, t));
    const detail = `${label} iso ${t}: ${JSON.stringify(cmp.unmatchedGpu.slice(0, 3))} vs ${JSON.stringify(cmp.unmatchedCpu.slice(0, 3))}`;
    expect(cmp.unmatchedGpu.length + cmp.unmatchedCpu.length, detail).toBe(0);
    expect(cmp.exact + cmp.withinOne).toBe(cpu.triangleCount);
    // Dequantized, in voxel index space: same area and bounding box within the quantization.
    const gpuMetrics = meshMetrics(await drawnSoup(iso));
    const cpuMetrics = meshMetrics(cpu.positions);
    if (cpu.triangleCount > 0) {
      // relative for large surfaces; tiny ones feel the quantization more
      expect(Math.abs(gpuMetrics.area - cpuMetrics.area)).toBeLessThan(0.005 * cpuMetrics.area + 0.002 * cpu.triangleCount);
      for (let a = 0; a < 3; a++) {
        expect(Math.abs(gpuMetrics.bbox!.min[a] - cpuMetrics.bbox!.min[a])).toBeLessThanOrEqual(VERTEX_TOLERANCE);
        expect(Math.abs(gpuMetrics.bbox!.max[a] - cpuMetrics.bbox!.max[a])).toBeLessThanOrEqual(VERTEX_TOLERANCE);
      }
    }
    shardsUsed = Math.max(shardsUsed, Math.ceil(stats.indices / Math.floor((c.options?.maxVertexBindingBytes ?? Infinity) / 4)));
  }
  if (c.options?.maxVertexBindingBytes) expect(shardsUsed).toBeGreaterThan(2);
}

describe('block marching cubes = serial marching cubes', () => {
  for (const c of CASES) {
    const name = `${c.dims.join('x')} ${c.kind}${c.options ? ' ' + JSON.stringify(c.options) : ''}${c.maxShardBytes ? ` stream shards of ${c.maxShardBytes} B` : ''}`;
    gpuTest(name, async ({ gpu }) => {
      const { device } = gpu;
      const values = makeField(c.dims, c.dims[0] * 7 + c.dims[1] * 131 + c.dims[2], c.kind);
      const stream = await compressVolume(device, values, c.dims, 16, c.maxShardBytes);
      if (c.maxShardBytes) expect(stream.shards.length).toBeGreaterThan(2);
      const decoded = await decodeVolume(device, stream);
      // groups of 1 block, of 3 (partial groups at the edges), the default
      for (const groupEdgeBlocks of [1, 3, undefined]) {
        const iso = await Isosurface.create(gpu, stream, { ...c.options, groupEdgeBlocks, ...testKernelOptions });
        await checkSurfaces(iso, decoded, c, `groups of ${groupEdgeBlocks ?? 'default'} blocks`);
        iso.destroy();
      }
      stream.destroy();
    });
  }
});
