// Scrubbing pipelined: the next isovalue is submitted while the previous
// surface's statistics are still being mapped (a bounded number in flight),
// each surface's statistics are its own (checked against a serial CPU
// marching cubes of the same decoded volume), growth still works when
// several attempts in flight were too small, and a submission that fails on
// the GPU rejects with a clear error instead of reporting a stale or empty
// surface, leaving the previous surface drawn.
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { IsosurfaceGpuError, IsosurfaceSupersededError, type IsosurfaceStats } from '../../../src/isosurface/types.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField, testKernelOptions } from './helpers.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';

const dims: Dims = [33, 29, 26];

async function setup(device: GPUDevice) {
  const values = makeField(dims, 11, 'blobs');
  const stream = await compressVolume(device, values, dims, 8);
  return { stream, decoded: await decodeVolume(device, stream) };
}

/** Counts submissions, and how many were made when each map resolved. */
function instrument(device: GPUDevice) {
  const queueProto = Object.getPrototypeOf(device.queue) as GPUQueue;
  const bufferProto = Object.getPrototypeOf(device.createBuffer({ size: 4, usage: GPUBufferUsage.COPY_DST })) as GPUBuffer;
  const original = { submit: queueProto.submit, mapAsync: bufferProto.mapAsync };
  /** submitsAtMapResolved[i]: submissions made when the i-th map resolved. */
  const log = { submits: 0, submitsAtMapResolved: [] as number[] };
  queueProto.submit = function (this: GPUQueue, buffers: Iterable<GPUCommandBuffer>) {
    log.submits++;
    return original.submit.call(this, buffers);
  };
  bufferProto.mapAsync = function (this: GPUBuffer, ...a: Parameters<GPUBuffer['mapAsync']>) {
    return original.mapAsync.apply(this, a).then((v) => {
      log.submitsAtMapResolved.push(log.submits);
      return v;
    });
  };
  return {
    log,
    restore() {
      queueProto.submit = original.submit;
      bufferProto.mapAsync = original.mapAsync;
    },
  };
}

describe('pipelined scrubbing', () => {
  gpuTest('back-to-back surfaces are submitted without waiting for maps; each statistic is its own surface', async ({ gpu }) => {
    const { stream, decoded } = await setup(gpu.device);
    const iso = await Isosurface.create(gpu, stream, {
      initialCacheSlots: 1 << 16,
      initialVertexCapacity: 1 << 20,
      maxSurfacesInFlight: 3,
      ...testKernelOptions,
    });
    const [lo, hi] = iso.info.valueRange;
    const values = [0.2, 0.55, 0.3, 0.7, 0.45].map((f) => Math.fround(lo + f * (hi - lo)));
    await iso.compute(values[0]); // pipelines warm
    const seen: IsosurfaceStats[] = [];
    const submitted: number[] = [];
    iso.onStats((s) => seen.push(s));
    iso.onSubmit((v) => submitted.push(v));
    const probe = instrument(gpu.device);
    let promises: Promise<IsosurfaceStats>[];
    try {
      // Three in flight at once; the fourth waits (pending), the fifth replaces it.
      promises = values.slice(1, 4).map((v) => iso.compute(v));
      expect(probe.log.submits).toBe(3); // all three submitted synchronously, before any map
      expect(submitted).toEqual(values.slice(1, 4));
      iso.setIsovalue(values[4]);
      expect(probe.log.submits).toBe(3);
      const results = await Promise.all(promises);
      await new Promise<void>((resolve) => {
        const check = () => (iso.busy ? setTimeout(check, 5) : resolve());
        check();
      });
      // The first statistics arrived after all three surfaces were submitted: none waited for a map.
      expect(probe.log.submitsAtMapResolved[0]).toBeGreaterThanOrEqual(3);
      expect(results.map((s) => s.isovalue)).toEqual(values.slice(1, 4));
    } finally {
      probe.restore();
    }
    expect(seen.map((s) => s.isovalue)).toEqual([...values.slice(1, 4), values[4]]);
    for (const s of seen) expect(s.triangles, `iso ${s.isovalue}`).toBe(marchingCubes(decoded, dims, s.isovalue).triangleCount);
    expect((await readVertices(iso)).length / 6).toBe(seen[seen.length - 1].triangles);
    iso.destroy();
    stream.destroy();
  });

  gpuTest('growth with attempts in flight: older ones that failed are superseded, the newest grows and is recomputed', async ({ gpu }) => {
    const { stream, decoded } = await setup(gpu.device);
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 1, initialVertexCapacity: 3, maxSurfacesInFlight: 3 });
    const [lo, hi] = iso.info.valueRange;
    const values = [0.3, 0.5, 0.4].map((f) => Math.fround(lo + f * (hi - lo)));
    const seen: number[] = [];
    iso.onStats((s) => seen.push(s.isovalue));
    const [a, b, c] = values.map((v) => iso.compute(v));
    await expect(a).rejects.toBeInstanceOf(IsosurfaceSupersededError);
    await expect(b).rejects.toBeInstanceOf(IsosurfaceSupersededError);
    const stats = await c;
    expect(stats.grew).toBe(true);
    expect(stats.triangles).toBe(marchingCubes(decoded, dims, values[2]).triangleCount);
    expect(seen).toEqual([values[2]]);
    // The grown buffers serve the others now.
    for (const v of values) expect((await iso.compute(v)).triangles).toBe(marchingCubes(decoded, dims, v).triangleCount);
    iso.destroy();
    stream.destroy();
  });

  gpuTest('a submission that fails on the GPU rejects with a clear error; the previous surface stays', async ({ gpu }) => {
    const { stream } = await setup(gpu.device);
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 1 << 16, initialVertexCapacity: 1 << 20, ...testKernelOptions });
    const [lo, hi] = iso.info.valueRange;
    const kept = await iso.compute(Math.fround(lo + 0.4 * (hi - lo)));
    expect(kept.triangles).toBeGreaterThan(0);
    const keptVertices = await readVertices(iso);
    const errors: Error[] = [];
    const stats: IsosurfaceStats[] = [];
    iso.onError((e) => errors.push(e));
    iso.onStats((s) => stats.push(s));
    // A buffer every computation binds (the cache's slot -> block map), destroyed: the submission is invalid.
    iso.pipeline.parts.cache.slotToBlock.destroy();
    const failed = await iso.compute(Math.fround(lo + 0.6 * (hi - lo))).catch((e: unknown) => e);
    expect(failed).toBeInstanceOf(IsosurfaceGpuError);
    expect((failed as Error).message).toMatch(/failed on the GPU \(validation error: .+\); the previous surface is kept/);
    expect(errors).toEqual([failed]);
    expect(stats).toEqual([]); // never { active: 0, triangles: 0 } or the previous counters
    expect(await readVertices(iso)).toEqual(keptVertices);
    iso.destroy();
    stream.destroy();
  });
});
