// The shared volume-opening path (page and CLI): what each kind of file is,
// what must be asked (page) or given (CLI), the errors users see, and that
// what is opened decodes to the same values as the codec's own path.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { ZfpEncoder } from '../../../src/zfp/encoder.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import {
  describeOpenedVolume,
  fittingRates,
  inspectVolumeFile,
  openDefaultVolume,
  openVolumeBytes,
  openVolumeFile,
} from '../../../src/volume/open-volume.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { sharedData } from '../../helpers/python.ts';

const volumes = join(sharedData, 'volumes');
const vectors = join(sharedData, 'zfp-vectors');
const read = (dir: string, name: string) => new Uint8Array(readFileSync(join(dir, name)));

describe('inspectVolumeFile', () => {
  it('reads headers, names and sizes', async () => {
    const h = await inspectVolumeFile(
      'hydrogen_atom_128x128x128_float32.rate8.zfp',
      read(volumes, 'hydrogen_atom_128x128x128_float32.rate8.zfp'),
    );
    expect(h).toMatchObject({ kind: 'zfp', dims: [128, 128, 128], rate: 8, missing: [], compresses: false });
    const raw = await inspectVolumeFile('neghip_66x66x66_uint8.raw', read(volumes, 'neghip_66x66x66_uint8.raw'));
    expect(raw).toMatchObject({ kind: 'raw', dims: [66, 66, 66], dtype: 'uint8', missing: [], compresses: true });
    const headerless = await inspectVolumeFile(
      'fuel_p8decoded_64x64x64_float32.rate4.zfp',
      read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.zfp'),
    );
    expect(headerless).toMatchObject({ kind: 'zfp-headerless', dims: [64, 64, 64], rate: 4, missing: [] });
  });

  it('says what is missing, with the rates that fit the size', async () => {
    const bytes = read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.zfp');
    const noRate = await inspectVolumeFile('fuel_64x64x64_float32.zfp', bytes);
    expect(noRate.missing).toEqual(['rate']);
    expect(noRate.fittingRates).toContain(4);
    const noName = await inspectVolumeFile('stream.zfp', bytes);
    expect(noName.missing).toEqual(['dims', 'rate']);
    const rawNoName = await inspectVolumeFile('scan.raw', read(volumes, 'neghip_66x66x66_uint8.raw'));
    expect(rawNoName.missing).toEqual(['dims', 'dtype']);
    expect(fittingRates([64, 64, 64], bytes.byteLength)).toEqual([4]);
  });

  it('rejects fixed-precision streams with the codec message naming the file', async () => {
    for (const f of ['fuel_64x64x64_float8.zfp', 'hydrogen_atom_128x128x128_float8.zfp', 'bonsai_256x256x256_float8.zfp']) {
      await expect(inspectVolumeFile(f, read(volumes, f))).rejects.toThrow(
        new RegExp(`^${f.replace(/\./g, '\\.')}: .*not a fixed-rate stream`),
      );
    }
  });

  it('rejects truncated and mis-sized files', async () => {
    const full = read(volumes, 'hydrogen_atom_128x128x128_float32.rate8.zfp');
    await expect(inspectVolumeFile('cut.zfp', full.subarray(0, 100_000))).rejects.toThrow(/^cut\.zfp: truncated/);
    await expect(inspectVolumeFile('neghip_64x64x64_uint8.raw', read(volumes, 'neghip_66x66x66_uint8.raw'))).rejects.toThrow(
      /^neghip_64x64x64_uint8\.raw: 64x64x64 uint8 is 262144 bytes, the file has 287496/,
    );
    await expect(
      inspectVolumeFile('x_64x64x64_float32.rate3.zfp', read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.zfp')),
    ).rejects.toThrow(/^x_64x64x64_float32\.rate3\.zfp: /);
  });

  it('reads multi-page TIFF files as volumes through libtiff', async () => {
    const tiff = join(sharedData, 'tiff');
    const bat = await inspectVolumeFile('morpholibj_bat-cochlea-volume.tif', read(tiff, 'morpholibj_bat-cochlea-volume.tif'));
    expect(bat).toMatchObject({ kind: 'tiff', dims: [121, 154, 114], dtype: 'uint8', missing: [], compresses: true });
    expect(bat.samples!.byteLength).toBe(121 * 154 * 114);
    const stack = await inspectVolumeFile('imagejs_stack.tif', read(tiff, 'imagejs_stack.tif'));
    expect(stack).toMatchObject({ kind: 'tiff', dims: [128, 128, 10], dtype: 'uint16' });
    await expect(inspectVolumeFile('imagejs_image-lzw.tif', read(tiff, 'imagejs_image-lzw.tif'))).rejects.toThrow(
      /^imagejs_image-lzw\.tif: 3 samples per pixel/,
    );
  });

  it('points non-volumes elsewhere', async () => {
    const las = read(join(sharedData, 'las'), 'laspy_simple.las');
    await expect(inspectVolumeFile('laspy_simple.las', las)).rejects.toThrow(
      /point cloud, not a volume; open it in the LIDAR example page/,
    );
    await expect(inspectVolumeFile('laspy_simple.las', las, { reader: 'command' })).rejects.toThrow(
      /point cloud, not a volume this command reads/,
    );
    await expect(inspectVolumeFile('notes.txt', new TextEncoder().encode('hello'), { reader: 'command' })).rejects.toThrow(
      /^notes\.txt: not a volume this command reads/,
    );
    await expect(inspectVolumeFile('notes.txt', new TextEncoder().encode('hello'))).rejects.toThrow(/^notes\.txt: not a volume/);
    await expect(
      inspectVolumeFile('bad.nrrd', new TextEncoder().encode('NRRD0004\ntype: float\ndimension: 2\nsizes: 2 2\nencoding: raw\n\n')),
    ).rejects.toThrow(/^bad\.nrrd: only 3D/);
  });
});

async function decode(device: GPUDevice, stream: Parameters<ZfpDecoder['readVolume']>[0]): Promise<Float32Array> {
  const decoder = await ZfpDecoder.create(device);
  try {
    return (await decoder.readVolume(stream))!;
  } finally {
    decoder.destroy();
  }
}

describe('openVolumeFile', () => {
  gpuTest('compresses a raw volume as the encoder does', async ({ gpu }) => {
    const bytes = read(volumes, 'neghip_66x66x66_uint8.raw');
    const facts = await inspectVolumeFile('neghip_66x66x66_uint8.raw', bytes);
    const opened = await openVolumeFile(gpu.device, facts, bytes, { rate: 6 });
    expect(opened).toMatchObject({ kind: 'raw', dims: [66, 66, 66], sourceDtype: 'uint8', rate: 6, compressedHere: true });
    const encoder = await ZfpEncoder.create(gpu.device);
    const ref = await encoder.compressToStream(bytes, 'uint8', [66, 66, 66], 6);
    expect(await opened.stream.readBytes()).toEqual(await ref.readBytes());
    opened.stream.destroy();
    ref.destroy();
    encoder.destroy();
  });

  gpuTest('opens a header-less stream with the shape and rate given by the user', async ({ gpu }) => {
    const bytes = read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.zfp');
    const facts = await inspectVolumeFile('stream.zfp', bytes);
    const opened = await openVolumeFile(gpu.device, facts, bytes, { dims: [64, 64, 64], rate: 4 });
    expect(opened.rate).toBe(4);
    const expected = new Float32Array(read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.decoded.raw').buffer);
    expect(await decode(gpu.device, opened.stream)).toEqual(expected);
    opened.stream.destroy();
    // A wrong rate is the codec's error, naming the user's file (not a made-up name).
    await expect(openVolumeFile(gpu.device, facts, bytes, { dims: [64, 64, 64], rate: 5 })).rejects.toThrow(/^stream\.zfp: /);
  });

  gpuTest('compresses a TIFF stack like the same samples as raw', async ({ gpu }) => {
    const tiff = join(sharedData, 'tiff');
    const facts = await inspectVolumeFile('morpholibj_bat-cochlea-volume.tif', read(tiff, 'morpholibj_bat-cochlea-volume.tif'));
    const opened = await openVolumeFile(gpu.device, facts, new Uint8Array(0), { rate: 4 });
    expect(opened).toMatchObject({ kind: 'tiff', dims: [121, 154, 114], sourceDtype: 'uint8', rate: 4 });
    const encoder = await ZfpEncoder.create(gpu.device);
    const ref = await encoder.compressToStream(facts.samples!, 'uint8', [121, 154, 114], 4);
    expect(await opened.stream.readBytes()).toEqual(await ref.readBytes());
    opened.stream.destroy();
    ref.destroy();
    encoder.destroy();
  });

  gpuTest('the built-in volume is the generated field at the rate chosen from it', async ({ gpu }) => {
    const opened = await openDefaultVolume(gpu.device);
    // a smooth float field in 0..1: rate 8 keeps its RMS error under 1e-4 of the range, rate 7 does not
    expect(opened).toMatchObject({ kind: 'default', dims: [128, 128, 128], rate: 8, defaultIsovalue: 0.5, rateChoice: { how: 'chosen' } });
    const same = loadZfpStream(gpu.device, await opened.stream.readBytes(), 'default.zfp');
    const a = await decode(gpu.device, opened.stream);
    const b = await decode(gpu.device, same);
    expect(a).toEqual(b);
    opened.stream.destroy();
    same.destroy();
  });
});

describe('openVolumeBytes (the CLI: what the file does not say comes with the call)', () => {
  gpuTest('header-less streams: the rate in the name first, else the one given, else a message', async ({ gpu }) => {
    const bytes = read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.zfp');
    const expected = new Float32Array(read(vectors, 'fuel_p8decoded_64x64x64_float32.rate4.decoded.raw').buffer);
    await expect(openVolumeBytes(gpu.device, bytes, 'fuel_64x64x64_float32.zfp')).rejects.toThrow(
      /^fuel_64x64x64_float32\.zfp: no zfp header and no rate in the name .*give it with --rate R \(rates that fit its size: 4\)$/,
    );
    const named = await openVolumeBytes(gpu.device, bytes, 'fuel_64x64x64_float32.rate4.zfp', { rate: 5 });
    const given = await openVolumeBytes(gpu.device, bytes, 'fuel_64x64x64_float32.zfp', { rate: 4 });
    for (const v of [named, given]) {
      expect(v).toMatchObject({ kind: 'zfp-headerless', rate: 4, compressedHere: false });
      expect(await decode(gpu.device, v.stream)).toEqual(expected);
      v.stream.destroy();
    }
    expect(describeOpenedVolume(named)).toMatch(/^header-less zfp file \(fixed rate 4.*\), used as is$/);
  });

  gpuTest('raw volumes: shape and type from the name or given; TIFF stacks as the page compresses them', async ({ gpu }) => {
    const bytes = read(volumes, 'neghip_66x66x66_uint8.raw');
    await expect(openVolumeBytes(gpu.device, bytes, 'scan.raw')).rejects.toThrow(
      /^scan\.raw: a raw volume needs its shape and type in the name/,
    );
    const given = await openVolumeBytes(gpu.device, bytes, 'scan.raw', { dims: [66, 66, 66], dtype: 'uint8', rate: 6 });
    const facts = await inspectVolumeFile('neghip_66x66x66_uint8.raw', bytes);
    const page = await openVolumeFile(gpu.device, facts, bytes, { rate: 6 });
    expect(await given.stream.readBytes()).toEqual(await page.stream.readBytes());
    expect(describeOpenedVolume(given)).toBe('raw 66x66x66 uint8 compressed on the GPU at rate 6');

    const tif = read(join(sharedData, 'tiff'), 'imagejs_stack.tif');
    const cli = await openVolumeBytes(gpu.device, tif, 'imagejs_stack.tif');
    const pageTiff = await openVolumeFile(gpu.device, await inspectVolumeFile('imagejs_stack.tif', tif), tif, {});
    // No rate given: both choose it from the data, the same way.
    expect(cli).toMatchObject({ kind: 'tiff', dims: [128, 128, 10], sourceDtype: 'uint16', rateChoice: { how: 'chosen' } });
    expect(pageTiff.rate).toBe(cli.rate);
    expect(await cli.stream.readBytes()).toEqual(await pageTiff.stream.readBytes());
    expect(describeOpenedVolume(cli)).toBe(`TIFF stack 128x128x10 uint16 compressed on the GPU at rate ${cli.rate}`);
    for (const v of [given, page, cli, pageTiff]) v.stream.destroy();
  });
});

describe('a volume wider than a surface can be (issue 36)', () => {
  gpuTest(
    'opens past 16384 voxels on an axis; past what a vertex can place, it is refused at open, before anything is compressed, with the limit named',
    async ({ gpu }) => {
      // 1 x 1 x 26730 float32: the page once chose a rate for seconds, then failed in the vertex format; it opens now
      const thin = await openVolumeBytes(gpu.device, new Uint8Array(26730 * 4), 'thin_1x1x26730_float32.raw');
      expect(thin.dims).toEqual([1, 1, 26730]);
      thin.stream.destroy();
      // more voxels on an axis than float32 positions hold whole: refused by its dims, before a rate is chosen
      const t0 = performance.now();
      await expect(openVolumeBytes(gpu.device, new Uint8Array(16777300), 'thin_1x1x16777300_uint8.raw')).rejects.toThrow(
        /^thin_1x1x16777300_uint8\.raw: 1x1x16777300 voxels: 16777300 along an axis.* whole voxels exact up to 16777216 per axis$/,
      );
      expect(performance.now() - t0).toBeLessThan(1000);
    },
  );
});
