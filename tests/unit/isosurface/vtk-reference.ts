// The GPU isosurfaces of the shared volumes against VTK's vtkMarchingCubes
// (shared/data/reference/mc.json), used by vtk-*.test.ts.
//
// The figures are for specific decoded data, so each entry's surfaces are
// computed from a zfp stream that decodes to exactly that data (checked by
// sha256 of our GPU decode): .rateR.zfp files are loaded as they are (they
// are the decoded data); raw and fixed-precision inputs are loaded as mc.json
// describes (tests/unit/mc/reference.ts: raw as is, uint8 converted, p8
// decoded by zfpy) and compressed by our encoder at the lowest rate among
// 8, 20, 32 that reproduces them bit for bit (fuel, hydrogen and bonsai p8: 8;
// the uint8 volumes: 20). Entries with the same decoded data share one run.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect } from 'vitest';
import type { GpuContext } from '../../../src/gpu/device.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { loadZfpStream, type ZfpGpuStream } from '../../../src/zfp/gpu-stream.ts';
import { loadMcVolume, sha256, SHARED_DATA, type McVolume } from '../mc/reference.ts';
import { compressVolume, decodeVolume, drawnSoup, testKernelOptions } from './helpers.ts';

export interface PreparedVolume {
  stream: ZfpGpuStream;
  /** How the stream was made. */
  source: string;
}

/** A stream whose GPU decode is bit for bit the data mc.json's figures are for. */
export async function prepareVolume(device: GPUDevice, v: McVolume, cacheDir: string): Promise<PreparedVolume> {
  if (v.kind === 'zfp-with-header') {
    const bytes = new Uint8Array(readFileSync(join(SHARED_DATA, v.file)));
    const stream = loadZfpStream(device, bytes, v.file);
    const decoded = await decodeVolume(device, stream);
    expect(sha256(decoded), `${v.file}: our decode`).toBe(v.decoded_sha256);
    return { stream, source: `${v.file} as is` };
  }
  const data = loadMcVolume(v, cacheDir);
  for (const rate of [8, 20, 32]) {
    const stream = await compressVolume(device, data, v.dims_xyz, rate);
    const decoded = await decodeVolume(device, stream);
    if (sha256(decoded) === sha256(data)) return { stream, source: `${v.file} compressed at rate ${rate} (lossless for it)` };
    stream.destroy();
  }
  throw new Error(`${v.file}: no rate up to 32 reproduces the data exactly`);
}

/** Computes every isovalue of the entries (which share decoded data) and checks them against VTK. */
export async function checkAgainstVtk(gpu: GpuContext, entries: McVolume[], cacheDir: string): Promise<string[]> {
  const log: string[] = [];
  const prepared = await prepareVolume(gpu.device, entries[0], cacheDir);
  // The budget is the device's default (half of maxBufferSize, at most 2 GiB) but at least 256 MiB: on a
  // device with WebGPU's default limits (ZFPISO_TEST_LIMITS=default) that default is 128 MiB, about what
  // bonsai's densest surface (2.4 M triangles, 1.2 M vertices) needs with the cache at its growth
  // headroom; this test is about the triangles, not the budget.
  const budget = Math.max(256 * 2 ** 20, Math.min(gpu.device.limits.maxBufferSize / 2, 2 ** 31));
  const iso = await Isosurface.create(gpu, prepared.stream, { memoryBudgetBytes: budget, ...testKernelOptions });
  try {
    for (const s of entries[0].isosurfaces) {
      const stats = await iso.compute(s.iso);
      const m = meshMetrics(await drawnSoup(iso));
      for (const v of entries) {
        const vtk = v.isosurfaces.find((x) => x.iso === s.iso)!.vtkMarchingCubes;
        const what = `${v.file} iso ${s.iso_nominal}`;
        // The classic table: the same triangles as VTK, so the same count.
        expect(stats.triangles, what).toBe(vtk.triangles);
        expect(m.triangles, what).toBe(vtk.triangles);
        // One welded vertex per cut grid edge: VTK's merged points.
        expect(stats.vertices, what).toBe(vtk.points);
        expect(Math.abs(m.area - vtk.area) / vtk.area, what).toBeLessThan(0.005);
        for (let a = 0; a < 3; a++) {
          expect(Math.abs(m.bbox!.min[a] - vtk.bbox!.min[a]), what).toBeLessThanOrEqual(1);
          expect(Math.abs(m.bbox!.max[a] - vtk.bbox!.max[a]), what).toBeLessThanOrEqual(1);
        }
        const bboxError = Math.max(
          ...[0, 1, 2].flatMap((a) => [Math.abs(m.bbox!.min[a] - vtk.bbox!.min[a]), Math.abs(m.bbox!.max[a] - vtk.bbox!.max[a])]),
        );
        log.push(
          `${what}: ${stats.triangles} triangles (= VTK), area ${((m.area / vtk.area - 1) * 100).toExponential(1)}%, bbox within ${bboxError.toFixed(4)}; ${stats.activeBlocks} active, ${stats.occupiedBlocks} occupied, ${stats.gpuMs.toFixed(0)} ms GPU`,
        );
      }
    }
  } finally {
    iso.destroy();
    prepared.stream.destroy();
  }
  log.unshift(`${entries.map((e) => e.file).join(' = ')}: ${prepared.source}`);
  return log;
}

/** mc.json entries grouped by the data they describe (same decoded sha256 / same isovalues). */
export function groupByData(volumes: McVolume[], dataKey: (v: McVolume) => string): McVolume[][] {
  const groups = new Map<string, McVolume[]>();
  for (const v of volumes) {
    const k = `${dataKey(v)}|${v.isosurfaces.map((s) => s.iso).join()}`;
    groups.set(k, [...(groups.get(k) ?? []), v]);
  }
  // A fixed-rate file, where the group has one, is the data itself: use it.
  const rank = (v: McVolume) => (v.kind === 'zfp-with-header' ? 0 : 1);
  return [...groups.values()].map((g) => g.sort((a, b) => rank(a) - rank(b)));
}
