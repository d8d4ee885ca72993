// The neuron page's isosurface path on a real TIFF stack: libtiff's samples
// (checked against tifffile in tests/unit/loaders) through tiffVolumeFacts,
// GPU compression and the shared openFirstSurface. Every vertex must lie
// where the stack, read as [page][y][x] (what the volume renderer uploads
// as texel (x, y, z)), crosses the isovalue: trilinear interpolation of the
// original samples at the vertex gives the isovalue. The same check with y
// or the page order flipped fails, so the check can tell orientations apart.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { chooseIsovalue } from '../../../src/app/iso-choice.ts';
import { openFirstSurface } from '../../../src/app/loading/first-surface.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { loadTiffStack, type TiffVolume } from '../../../src/loaders/tiff.ts';
import { openVolumeFile, tiffVolumeFacts } from '../../../src/volume/open-volume.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { sharedData } from '../../helpers/python.ts';

const tiffDir = join(sharedData, 'tiff');
const load = (name: string) => loadTiffStack({ name, bytes: new Uint8Array(readFileSync(join(tiffDir, name))) });

/** Trilinear interpolation of a one-sample-per-pixel stack at (x, y, z) in voxel index space, [page][y][x] layout. */
function sample(v: TiffVolume, x: number, y: number, z: number): number {
  const [nx, ny, nz] = v.dims;
  const at = (i: number, j: number, k: number) => v.data[(Math.min(k, nz - 1) * ny + Math.min(j, ny - 1)) * nx + Math.min(i, nx - 1)];
  const [i, j, k] = [Math.floor(x), Math.floor(y), Math.floor(z)];
  const [fx, fy, fz] = [x - i, y - j, z - k];
  let s = 0;
  for (let c = 0; c < 8; c++) {
    const [dx, dy, dz] = [c & 1, (c >> 1) & 1, c >> 2];
    s += at(i + dx, j + dy, k + dz) * (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
  }
  return s;
}

describe('the isosurface of a TIFF stack (neuron page path)', () => {
  gpuTest('lies where the stack, read as [page][y][x], crosses the isovalue', async ({ gpu }) => {
    const name = 'imagejs_stack.tif';
    const v = await load(name);
    expect(v).toMatchObject({ dims: [128, 128, 10], dtype: 'uint16', samplesPerPixel: 1 });
    const facts = tiffVolumeFacts(name, v, 0, { channels: 'mean' });
    expect(facts).toMatchObject({ kind: 'tiff', dims: [128, 128, 10], dtype: 'uint16' });
    // A high rate, so the decoded blocks are the samples to within a fraction of a grey level.
    const opened = await openVolumeFile(gpu.device, facts, new Uint8Array(0), { rate: 24 });
    const surface = await openFirstSurface(gpu, opened, { chooseIso: (_o, iso, ranges) => chooseIsovalue(ranges, iso.info.valueRange) });
    try {
      const { iso, initialIso, firstStats } = surface;
      expect(firstStats.triangles).toBeGreaterThan(1000);
      const mesh = await iso.readMesh();
      const p = decodeVertices(mesh.vertices, mesh.vertices.length / 3);
      const [lo, hi] = iso.info.valueRange;
      const tolerance = 0.01 * (hi - lo);
      const [nx, ny, nz] = v.dims;
      const misses = (flip: (x: number, y: number, z: number) => [number, number, number]) => {
        let n = 0;
        for (let i = 0; i < p.length; i += 3) {
          const [x, y, z] = flip(p[i], p[i + 1], p[i + 2]);
          if (Math.abs(sample(v, x, y, z) - initialIso) > tolerance) n++;
        }
        return n / (p.length / 3);
      };
      // (Observed: none off with the right orientation; 89-99% off with an axis flipped.)
      expect(misses((x, y, z) => [x, y, z])).toBeLessThan(0.005);
      expect(misses((x, y, z) => [x, ny - 1 - y, z])).toBeGreaterThan(0.5);
      expect(misses((x, y, z) => [x, y, nz - 1 - z])).toBeGreaterThan(0.5);
      expect(misses((x, y, z) => [nx - 1 - x, y, z])).toBeGreaterThan(0.5);
    } finally {
      surface.iso.destroy();
      surface.opened.stream.destroy();
    }
  });

  it("multi-channel stacks: the channels' mean as float32, or refused for the main page", async () => {
    const name = 'imagejs_image-lzw.tif';
    const v = await load(name);
    expect(v.samplesPerPixel).toBe(3);
    expect(() => tiffVolumeFacts(name, v, 0)).toThrow(/^imagejs_image-lzw\.tif: 3 samples per pixel/);
    const facts = tiffVolumeFacts(name, v, 0, { channels: 'mean' });
    expect(facts.dtype).toBe('float32');
    const mean = new Float32Array(facts.samples!.buffer, facts.samples!.byteOffset, facts.samples!.byteLength / 4);
    expect(mean.length).toBe(v.dims[0] * v.dims[1] * v.dims[2]);
    for (const i of [0, 17, 1000, mean.length - 1])
      expect(mean[i]).toBeCloseTo((v.data[3 * i] + v.data[3 * i + 1] + v.data[3 * i + 2]) / 3, 4);
  });
});
