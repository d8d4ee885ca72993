// `npm run bench:zfp`: whole-volume decode and encode throughput of the WGSL
// zfp codec (GB/s of float32 data; GPU time of the kernel pass from timestamp
// queries, or queue wall time where there are none), median of 10 runs after
// a discarded first, next to zfpy's serial C codec (zfp 1.0.1) on the same
// file in the same run, as a ratio. The whole-volume decode and the
// block-list decode (the cache fill: every block of the file into its own
// slot, dispatched indirectly) run on each kernel family of ZfpDecoder
// (emulator path, GPU path), both forced, their repeats interleaved (path A,
// path B, path A, ...) so that load on a shared machine hits both alike. Also
// the block-range pass (one kernel for both paths).
//
//   node benchmarks/run.mjs benchmarks/zfp.ts [--repeats N] [--paths emulator,gpu] [FILE.zfp ...]
import { execFileSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { basename, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { GpuTimer } from '../src/gpu/timing.ts';
import type { PrimitivePath } from '../src/primitives/dispatch-records.ts';
import { ZfpDecoder } from '../src/zfp/decoder.ts';
import { ZfpEncoder } from '../src/zfp/encoder.ts';
import { openZfpStream, planZfpStream } from '../src/zfp/format.ts';
import { ZfpGpuStream } from '../src/zfp/gpu-stream.ts';
import { formatDims } from '../src/core/naming.ts';
import { printTable, repeat, summarize, writeJson, type Stats } from './lib/report.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const volumes = join(root, '..', 'shared', 'data', 'volumes');
const DEFAULT_FILES = [join(volumes, 'bonsai_256x256x256_float32.rate4.zfp'), join(volumes, 'hydrogen_atom_128x128x128_float32.rate8.zfp')];

const args = process.argv.slice(2);
let repeats = 11; // 10 measured after the discarded first
const files: string[] = [];
let paths: PrimitivePath[] = ['emulator', 'gpu'];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--repeats') repeats = Number(args[++i]) + 1;
  else if (args[i] === '--paths') paths = args[++i].split(',').filter((p): p is PrimitivePath => p === 'emulator' || p === 'gpu');
  else files.push(args[i]);
}
if (files.length === 0) files.push(...DEFAULT_FILES);

const ZFPY = `
import sys, json, time, numpy as np, zfpy
path, repeats = sys.argv[1], int(sys.argv[2])
data = open(path, 'rb').read()
h = zfpy.header(data)
def timed(f):
    out, ts = None, []
    for _ in range(repeats):
        t = time.perf_counter(); out = f(); ts.append(time.perf_counter() - t)
    return out, ts
dec, tdec = timed(lambda: zfpy.decompress_numpy(data))
rate = h['config']['rate']
_, tenc = timed(lambda: zfpy.compress_numpy(dec, rate=rate, write_header=True))
print(json.dumps({'decode_s': tdec, 'encode_s': tenc}))
`;

function python(): string {
  return join(root, '.venv', 'bin', 'python');
}

function summarizeSeconds(all: number[]): Stats {
  const sorted = all.slice(1).sort((a, b) => a - b);
  const mid = sorted.length >> 1;
  const median = sorted.length % 2 ? sorted[mid] : (sorted[mid - 1] + sorted[mid]) / 2;
  return {
    samples: all.slice(1),
    median,
    mean: sorted.reduce((s, x) => s + x, 0) / sorted.length,
    min: sorted[0],
    max: sorted[sorted.length - 1],
  };
}

/** Runs each of `measures` once per round, `repeats` rounds; the stats of each. */
async function repeatInterleaved(repeats: number, measures: (() => Promise<number>)[]): Promise<Stats[]> {
  const all = measures.map(() => [] as number[]);
  for (let i = 0; i < repeats; i++) for (let m = 0; m < measures.length; m++) all[m].push(await measures[m]());
  return all.map((a) => summarize(a));
}

async function main(): Promise<void> {
  const gpu = await requestNodeGpu({ label: 'bench.zfp', onFailure: (f) => console.error(`WebGPU ${f.kind}: ${f.message}`) });
  const { device } = gpu;
  const adapter = describeAdapter(gpu.adapter);
  console.log(`adapter: ${adapter}`);
  const decoder = await ZfpDecoder.create(device);
  const encoder = await ZfpEncoder.create(device);
  const listDecoders = await Promise.all(paths.map((path) => ZfpDecoder.create(device, { path })));
  const timer = new GpuTimer(device, 16);
  const rows: (string | number)[][] = [];
  const results: unknown[] = [];

  for (const path of files) {
    const bytes = new Uint8Array(readFileSync(path));
    const info = openZfpStream(bytes, basename(path));
    const floatBytes = info.dims[0] * info.dims[1] * info.dims[2] * 4;
    const stream = ZfpGpuStream.upload(device, info, bytes);
    const volume = decoder.decodeVolume(stream); // also the encoder's input
    const target = encoder.createStream(planZfpStream(info.fileName, info.dims, info.rate, info.hasHeader), 'float32');

    const timeOne = async (record: (enc: GPUCommandEncoder, frame: ReturnType<GpuTimer['begin']>) => void, label: string) => {
      const frame = timer.begin();
      const enc = device.createCommandEncoder({ label: `bench.${label}` });
      record(enc, frame);
      frame.resolve(enc);
      device.queue.submit([enc.finish()]);
      frame.submitted();
      return (await frame.read()).totalMs / 1000;
    };
    const volumeDecodes = await repeatInterleaved(
      repeats,
      listDecoders.map(
        (d) => () =>
          timeOne(
            (enc, frame) => d.encodeDecodeVolume(enc, { stream, output: volume, timestampWrites: frame.pass('decode') }),
            `decode.${d.path}`,
          ),
      ),
    );
    const ranges = device.createBuffer({
      label: 'bench.ranges',
      size: Math.max(8, ZfpDecoder.rangesBytes(stream)),
      usage: GPUBufferUsage.STORAGE,
    });
    const rangePass = await repeat(repeats, () =>
      timeOne((enc, frame) => decoder.encodeBlockRanges(enc, { stream, ranges, timestampWrites: frame.pass('ranges') }), 'ranges'),
    );
    ranges.destroy();
    const encode = await repeat(repeats, () =>
      timeOne((enc, frame) => {
        for (let s = 0; s < target.shards.length; s++) {
          const inputZPlane = 0; // the whole decoded volume is the input
          encoder.encode(enc, {
            input: volume,
            dtype: 'float32',
            inputZPlane,
            stream: target,
            shard: s,
            timestampWrites: frame.pass(`encode${s}`),
          });
        }
      }, 'encode'),
    );

    // The block list: blocks [0, n) into slots [0, n), n as many as one binding of slots holds.
    const listBlocks = Math.min(info.blockCount, Math.floor(device.limits.maxStorageBufferBindingSize / 256));
    const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST;
    const ids = device.createBuffer({ label: 'bench.blockIds', size: listBlocks * 4, usage });
    device.queue.writeBuffer(
      ids,
      0,
      Uint32Array.from({ length: listBlocks }, (_, i) => i),
    );
    const count = device.createBuffer({ label: 'bench.count', size: 4, usage });
    device.queue.writeBuffer(count, 0, new Uint32Array([listBlocks]));
    const slots = device.createBuffer({ label: 'bench.slots', size: listBlocks * 256, usage: GPUBufferUsage.STORAGE });
    const blockList: Record<string, unknown> = {};
    const listRows: (string | number)[][] = [];
    const listTimes = await repeatInterleaved(
      repeats,
      listDecoders.map(
        (d) => () =>
          timeOne(
            (enc, frame) =>
              d.encodeDecodeBlocks(enc, {
                stream,
                blockIds: ids,
                slotIds: ids,
                count: { buffer: count, offset: 0 },
                slots,
                timestampWrites: frame.pass('decodeBlocks'),
              }),
            `decodeBlocks.${d.path}`,
          ),
      ),
    );
    for (const [k, d] of listDecoders.entries()) {
      const t = listTimes[k];
      const listBytes = listBlocks * 256;
      listRows.push([`decode blocks (${d.path} path)`, listBytes / t.median / 1e9, t.median * 1000]);
      blockList[d.path] = { blocks: listBlocks, gbPerSecond: listBytes / t.median / 1e9, seconds: t };
    }
    for (const b of [ids, count, slots]) b.destroy();

    const zfpy = JSON.parse(execFileSync(python(), ['-c', ZFPY, path, String(repeats)], { encoding: 'utf8', maxBuffer: 1 << 26 })) as {
      decode_s: number[];
      encode_s: number[];
    };
    const zdec = summarizeSeconds(zfpy.decode_s);
    const zenc = summarizeSeconds(zfpy.encode_s);
    const gbs = (s: number) => floatBytes / s / 1e9;
    const name = `${basename(path)} (${formatDims(info.dims)}, rate ${info.rate})`;
    const decode: Record<string, unknown> = {};
    const decodeRatio: Record<string, number> = {};
    for (const [k, d] of listDecoders.entries()) {
      const t = volumeDecodes[k];
      rows.push([
        name,
        `decode volume (${d.path} path)`,
        gbs(t.median),
        gbs(zdec.median),
        gbs(t.median) / gbs(zdec.median),
        t.median * 1000,
      ]);
      decode[d.path] = { gbPerSecond: gbs(t.median), seconds: t };
      decodeRatio[d.path] = gbs(t.median) / gbs(zdec.median);
    }
    rows.push([name, 'encode', gbs(encode.median), gbs(zenc.median), gbs(encode.median) / gbs(zenc.median), encode.median * 1000]);
    // GB/s of slot data (256 bytes per block, partial blocks included); zfpy has no counterpart.
    for (const [op, gb, ms] of listRows) rows.push([name, op, gb, '', '', ms]);
    // GB/s of float32 data the ranges cover
    rows.push([name, 'block ranges', gbs(rangePass.median), '', '', rangePass.median * 1000]);
    results.push({
      file: path,
      dims: info.dims,
      rate: info.rate,
      bitsPerBlock: info.bitsPerBlock,
      compressedBytes: bytes.byteLength,
      float32Bytes: floatBytes,
      decode,
      blockRanges: { gbPerSecond: gbs(rangePass.median), seconds: rangePass },
      encode: { gbPerSecond: gbs(encode.median), seconds: encode },
      zfpySerial: {
        decode: { gbPerSecond: gbs(zdec.median), seconds: zdec },
        encode: { gbPerSecond: gbs(zenc.median), seconds: zenc },
      },
      blockList,
      ratio: { decode: decodeRatio, encode: gbs(encode.median) / gbs(zenc.median) },
    });
    volume.destroy();
    target.destroy();
    stream.destroy();
  }

  printTable(
    `zfp fixed-rate codec, GB/s of float32 data, median of ${repeats - 1} (first run discarded); ours: ${timer.source}`,
    ['file', 'op', 'WebGPU GB/s', 'zfpy serial GB/s', 'ratio', 'WebGPU ms'],
    rows,
  );
  if (gpu.adapter.software)
    console.log('\nnote: the adapter is a software rasterizer (SwiftShader on the CPU): these are not GPU figures.');
  const slug = (gpu.adapter.architecture || gpu.adapter.vendor || 'unknown')
    .toLowerCase()
    .replace(/[^a-z0-9]+/g, '-')
    .replace(/^-|-$/g, '');
  writeJson(join(root, 'benchmarks', 'results', `zfp-${slug}.json`), {
    benchmark: 'zfp',
    date: new Date().toISOString(),
    adapter: gpu.adapter,
    adapterDescription: adapter,
    timing: timer.source === 'timestamp-query' ? 'GPU time of the kernel pass (timestamp queries)' : 'queue wall time from submit to done',
    zfpyTiming: 'time.perf_counter around zfpy.decompress_numpy / compress_numpy only (serial C, zfp 1.0.1)',
    repeats: repeats - 1,
    results,
  });
  timer.destroy();
  decoder.destroy();
  for (const d of listDecoders) d.destroy();
  encoder.destroy();
  device.destroy();
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
