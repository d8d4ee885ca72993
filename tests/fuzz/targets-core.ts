// Fuzz targets of the TypeScript readers: zfp (with header and header-less),
// raw volumes, NRRD and SWC. Each opens a file the way the page and the CLI
// do: `describeFile` (what `cli info` prints; it must never throw), then
// `openVolumeBytes` (inspectVolumeFile + openVolumeFile, the page's and
// `cli extract`'s path, up to the zfp stream on the GPU); SWC through
// parseSwc + checkSwcTree + swcStats (the neuron page and its checks).

import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { gzipSync } from 'node:zlib';
import { describeFile } from '../../src/formats/describe.ts';
import type { GpuContext } from '../../src/gpu/device.ts';
import { requestNodeGpu } from '../../src/gpu/node-gpu.ts';
import { checkSwcTree, parseSwc, SwcError, swcStats } from '../../src/loaders/swc.ts';
import { encoderFor, openVolumeBytes, VolumeFileError } from '../../src/volume/open-volume.ts';
import { ZfpFormatError } from '../../src/zfp/format.ts';
import { mulberry32 } from '../../src/util/random.ts';
import type { FuzzSeed, FuzzTarget } from './target.ts';

const sharedData = join(import.meta.dirname, '..', '..', '..', 'shared', 'data');

function shared(...parts: string[]): FuzzSeed[] {
  const path = join(sharedData, ...parts);
  return existsSync(path) ? [{ name: parts[parts.length - 1], bytes: new Uint8Array(readFileSync(path)) }] : [];
}

let gpu: Promise<GpuContext> | undefined;
/** One Dawn device for all volume targets (SwiftShader here). */
export function fuzzGpu(): Promise<GpuContext> {
  gpu ??= requestNodeGpu({ label: 'fuzz.device', onFailure: (f) => console.error(`fuzz device: ${f.kind}: ${f.message}`) });
  return gpu;
}

/** A smooth float32 field with a little noise (seeded). */
function field(dims: [number, number, number], seed: number): Float32Array {
  const rng = mulberry32(seed);
  const [X, Y, Z] = dims;
  const out = new Float32Array(X * Y * Z);
  for (let z = 0, i = 0; z < Z; z++) {
    for (let y = 0; y < Y; y++) {
      for (let x = 0; x < X; x++, i++) out[i] = Math.sin(x * 0.7) * Math.cos(y * 0.5) + z * 0.1 + rng() * 0.05;
    }
  }
  return out;
}

const bytesOf = (a: ArrayBufferView) => new Uint8Array(a.buffer, a.byteOffset, a.byteLength);

/** Opens as `cli info` and then as the page / `cli extract`; frees the stream. */
async function openVolume(name: string, bytes: Uint8Array): Promise<string> {
  // `cli info` reads the first 4 KiB and the size; it reports problems, never throws.
  describeFile(name, bytes.length, bytes.subarray(0, 4096));
  const { device } = await fuzzGpu();
  const scopes: GPUErrorFilter[] = ['validation', 'out-of-memory', 'internal'];
  for (const s of scopes) device.pushErrorScope(s);
  let summary = '';
  let failure: unknown;
  try {
    const v = await openVolumeBytes(device, bytes, name, { reader: 'command' });
    summary = `${v.kind} ${v.dims.join('x')} rate ${v.rate}${v.notes.length ? ` (${v.notes.join('; ')})` : ''}`;
    v.stream.destroy();
  } catch (e) {
    failure = e;
  }
  const errors: string[] = [];
  for (let i = 0; i < scopes.length; i++) {
    const e = await device.popErrorScope();
    if (e) errors.push(e.message);
  }
  if (errors.length > 0) throw new Error(`WebGPU error while opening ${name}: ${errors.join('; ')}`);
  if (failure !== undefined) throw failure;
  return summary;
}

function volumeRejection(e: unknown, name: string): boolean {
  return (e instanceof VolumeFileError || e instanceof ZfpFormatError) && e.message.includes(name);
}

const zfpTarget: FuzzTarget = {
  reader: 'zfp',
  async seeds() {
    const { device } = await fuzzGpu();
    const encoder = await encoderFor(device);
    const seeds: FuzzSeed[] = [];
    for (const [dims, rate] of [
      [[13, 9, 6], 8],
      [[16, 16, 16], 2],
      [[5, 7, 9], 40], // > 2048 bits per block: zfp's 148-bit header
    ] as [[number, number, number], number][]) {
      const data = bytesOf(field(dims, dims[0]));
      const withHeader = await encoder.compress(data, 'float32', dims, rate, { header: true, fileName: 'seed' });
      seeds.push({ name: `seed_${dims.join('x')}_float32.rate${rate}.zfp`, bytes: withHeader.bytes });
      const plain = await encoder.compress(data, 'float32', dims, rate, { header: false, fileName: 'seed' });
      seeds.push({ name: `seed_${dims.join('x')}_float32.raw.crate${rate}.zfp`, bytes: plain.bytes });
    }
    return [...seeds, ...shared('zfp-vectors', 'fuel_p8decoded_64x64x64_float32.rate2.hdr.zfp')];
  },
  open: openVolume,
  isCleanRejection: volumeRejection,
};

const rawTarget: FuzzTarget = {
  reader: 'raw',
  async seeds() {
    const f = field([13, 9, 6], 7);
    const n = f.length;
    return [
      { name: 'seed_13x9x6_float32.raw', bytes: bytesOf(f) },
      { name: 'seed_13x9x6_float64.raw', bytes: bytesOf(Float64Array.from(f)) },
      { name: 'seed_13x9x6_uint8.raw', bytes: Uint8Array.from(f, (v) => (v + 1) * 100) },
      { name: 'seed_13x9x6_int16.raw', bytes: bytesOf(Int16Array.from(f, (v) => v * 1000)) },
      { name: 'seed_9x9x9_uint16.raw', bytes: bytesOf(Uint16Array.from({ length: 729 }, (_, i) => (i * 37) % 4096)) },
      { name: 'seed_4x4x4_int8.raw', bytes: Uint8Array.from({ length: 64 }, (_, i) => i * 3) },
      { name: `seed_${n}x1x1_float32.raw`, bytes: bytesOf(f) },
      ...shared('volumes', 'ironProt_68x68x68_uint8.raw'),
    ];
  },
  open: openVolume,
  isCleanRejection: volumeRejection,
};

function nrrd(header: string[], payload: Uint8Array): Uint8Array {
  const text = new TextEncoder().encode(`NRRD0004\n${header.join('\n')}\n\n`);
  const out = new Uint8Array(text.length + payload.length);
  out.set(text);
  out.set(payload, text.length);
  return out;
}

const nrrdTarget: FuzzTarget = {
  reader: 'nrrd',
  async seeds() {
    const f = field([11, 7, 5], 3);
    const u8 = Uint8Array.from(f, (v) => (v + 1) * 100);
    const u16 = Uint16Array.from(f, (v) => (v + 1) * 9000);
    const be16 = new Uint8Array(u16.byteLength);
    const dv = new DataView(be16.buffer);
    u16.forEach((v, i) => dv.setUint16(2 * i, v, false));
    const f64 = Float64Array.from(f);
    return [
      {
        name: 'float.nrrd',
        bytes: nrrd(['type: float', 'dimension: 3', 'sizes: 11 7 5', 'encoding: raw', 'endian: little', 'spacings: 1 1 2.5'], bytesOf(f)),
      },
      { name: 'uchar-gzip.nrrd', bytes: nrrd(['type: uchar', 'dimension: 3', 'sizes: 11 7 5', 'encoding: gzip'], gzipSync(u8)) },
      {
        name: 'ushort-big.nrrd',
        bytes: nrrd(
          [
            'type: unsigned short',
            'dimension: 3',
            'sizes: 11 7 5',
            'encoding: raw',
            'endian: big',
            'space directions: (1,0,0) (0,1,0) (0,0,3)',
          ],
          be16,
        ),
      },
      {
        name: 'double-4d.nrrd',
        bytes: nrrd(['type: double', 'dimension: 4', 'sizes: 1 11 7 5', 'encoding: raw', 'endian: little'], bytesOf(f64)),
      },
      {
        name: 'float-gzip.nrrd',
        bytes: nrrd(['type: float', 'dimension: 3', 'sizes: 11 7 5', 'encoding: gz', 'endian: little'], gzipSync(bytesOf(f))),
      },
    ];
  },
  open: openVolume,
  isCleanRejection: volumeRejection,
};

const swcTarget: FuzzTarget = {
  reader: 'swc',
  async seeds() {
    const lines = ['# generated', '1 1 0 0 0 5 -1'];
    for (let i = 2; i <= 40; i++) lines.push(`${i} ${2 + (i % 3)} ${i} ${(i * 7) % 11} ${i % 5}.5 ${1 / i} ${i < 6 ? 1 : i - 3}`);
    return [
      { name: 'generated.swc', bytes: new TextEncoder().encode(lines.join('\n') + '\n') },
      ...shared('swc', 'neurom_simple.swc'),
      ...shared('swc', 'neurom_Neuron.swc'),
    ];
  },
  async open(name, bytes) {
    // What the neuron page does: File.text() (UTF-8), parse, check, statistics.
    const tree = parseSwc(new TextDecoder().decode(bytes), name);
    const check = checkSwcTree(tree);
    const stats = swcStats(tree);
    return `${stats.sampleCount} samples, ${check.drawnSegments} segments drawn${check.problems.length ? `; ${check.problems.join('; ')}` : ''}`;
  },
  isCleanRejection: (e, name) => e instanceof SwcError && e.message.includes(name),
};

export const coreFuzzTargets: FuzzTarget[] = [zfpTarget, rawTarget, nrrdTarget, swcTarget];
