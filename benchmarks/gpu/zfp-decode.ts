// bench:gpu's zfp decode: GB/s of decoded float32 written by the WGSL zfp
// decoder, per kernel family (emulator path, GPU path; 'auto' picks one),
// GPU time from timestamps, median after a discarded first:
// - whole volume: the reference file (its decode's SHA-256 equals zfpy's, from
//   shared/data/reference/mc.json) and the generated volume compressed on
//   the GPU;
// - sharded pool: the same streams cut into chunks (each a zfp stream of its
//   own, as a store holds them) in a ChunkedVolume pool split over several
//   storage bindings, every block decoded into its slot (the cache fill of a
//   streamed level); the reference file's slots equal its whole decode.
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { readF32 } from '../../src/gpu/buffers.ts';
import { GpuTimer } from '../../src/gpu/timing.ts';
import type { PrimitivePath } from '../../src/primitives/dispatch-records.ts';
import { compressOnGpu } from '../../src/volume/open-volume.ts';
import { ChunkedVolume, type ChunkLevelLayout } from '../../src/zfp/chunked-volume.ts';
import { ZfpDecoder } from '../../src/zfp/decoder.ts';
import { openZfpStream, planZfpStream, type ZfpStreamInfo } from '../../src/zfp/format.ts';
import { ZfpGpuStream } from '../../src/zfp/gpu-stream.ts';
import { writeZfpHeader } from '../../src/zfp/header.ts';
import { summarize } from '../lib/report.ts';
import type { BenchRun } from './context.ts';
import { generatedField } from './gen-field.ts';

const SECTION = 'zfp decode';

interface McEntry {
  file: string;
  decoded_sha256?: string;
}

export function referenceEntry(data: string, file: string): McEntry & Record<string, unknown> {
  const mc = JSON.parse(readFileSync(join(data, 'reference', 'mc.json'), 'utf8')) as { volumes: (McEntry & Record<string, unknown>)[] };
  const e = mc.volumes.find((v) => v.file === `volumes/${file}`);
  if (!e) throw new Error(`reference/mc.json has no entry for volumes/${file}`);
  return e;
}

/**
 * The chunks of a whole fixed-rate stream with a 96-bit header: each chunk a
 * stream of its own (header, its blocks in raster order); zfp codes every
 * block alone, so the bits are the whole stream's. Dims must be multiples of
 * the chunk edge and blocks whole bytes.
 */
export function chunkStreams(whole: Uint8Array, info: ZfpStreamInfo, edge: number): { layout: ChunkLevelLayout; chunks: Uint8Array[] } {
  const [nx, ny, nz] = info.dims;
  if ([nx, ny, nz].some((n) => n % edge !== 0)) throw new Error(`${info.fileName}: ${info.dims.join('x')} is not whole chunks of ${edge}`);
  const plan = planZfpStream('chunk', [edge, edge, edge], info.rate, true);
  if (info.payloadBitOffset % 8 !== 0 || plan.payloadBitOffset % 8 !== 0 || info.bitsPerBlock % 8 !== 0)
    throw new Error(`${info.fileName}: chunking needs whole-byte blocks and headers`);
  const header = writeZfpHeader([edge, edge, edge], info.bitsPerBlock).bytes;
  const blockBytes = info.bitsPerBlock / 8;
  const [gx, gy, gz] = [nx / edge, ny / edge, nz / edge];
  const [bx, by] = [nx / 4, ny / 4];
  const cb = edge / 4;
  const chunks: Uint8Array[] = [];
  const start = info.payloadBitOffset / 8;
  for (let cz = 0; cz < gz; cz++)
    for (let cy = 0; cy < gy; cy++)
      for (let cx = 0; cx < gx; cx++) {
        const out = new Uint8Array(plan.paddedBytes);
        out.set(header);
        let o = plan.payloadBitOffset / 8;
        for (let z = 0; z < cb; z++)
          for (let y = 0; y < cb; y++) {
            // a row of cb blocks is contiguous in the whole stream
            const b = cx * cb + bx * (cy * cb + y + by * (cz * cb + z));
            out.set(whole.subarray(start + b * blockBytes, start + (b + cb) * blockBytes), o);
            o += cb * blockBytes;
          }
        chunks.push(out);
      }
  return {
    layout: {
      dims: [nx, ny, nz],
      chunkEdge: edge,
      chunkGrid: [gx, gy, gz],
      rate: info.rate,
      chunkBytes: plan.paddedBytes,
      name: `${info.fileName} in ${edge}^3 chunks`,
    },
    chunks,
  };
}

export async function zfpDecodeSection(run: BenchRun): Promise<unknown> {
  const { device } = run.gpu;
  const paths: PrimitivePath[] = ['emulator', 'gpu'];
  const decoders = await Promise.all(paths.map((path) => ZfpDecoder.create(device, { path })));
  const autoDecoder = await ZfpDecoder.create(device);
  const autoPath = autoDecoder.path;
  autoDecoder.destroy();
  const timer = new GpuTimer(device, 4);
  const repeats = run.plan.decodeRepeats + 1;
  const rows: (string | number)[][] = [];
  const records: unknown[] = [];
  const timed = async (label: string, record: (enc: GPUCommandEncoder, tw: GPUComputePassTimestampWrites | undefined) => void) => {
    await run.warmUp((enc) => record(enc, undefined));
    const all: number[] = [];
    for (let i = 0; i < repeats; i++) {
      const frame = timer.begin();
      const enc = device.createCommandEncoder({ label: `benchGpu.${label}` });
      record(enc, frame.pass(label));
      frame.resolve(enc);
      device.queue.submit([enc.finish()]);
      frame.submitted();
      all.push((await frame.read()).totalMs);
    }
    return summarize(all);
  };

  const volumes: { key: string; stream: ZfpGpuStream; bytes: Uint8Array; sha256?: string }[] = [];
  const refFile = run.plan.decodeVolume;
  const refBytes = new Uint8Array(readFileSync(join(run.paths.data, 'volumes', refFile)));
  const refInfo = openZfpStream(refBytes, refFile);
  volumes.push({
    key: refFile,
    stream: ZfpGpuStream.upload(device, refInfo, refBytes),
    bytes: refBytes,
    sha256: referenceEntry(run.paths.data, refFile).decoded_sha256,
  });
  const g = run.plan.genEdge;
  const field = generatedField([g, g, g]);
  const genName = `gen_${g}x${g}x${g}_float32 (rate ${run.plan.genRate})`;
  const genStream = await compressOnGpu(device, new Uint8Array(field.buffer), 'float32', [g, g, g], run.plan.genRate, genName);
  volumes.push({ key: genName, stream: genStream, bytes: await genStream.readBytes() });

  try {
    for (const v of volumes) {
      const { info } = v.stream;
      const floatBytes = info.dims[0] * info.dims[1] * info.dims[2] * 4;
      const output = decoders[0].decodeVolume(v.stream);
      for (const d of decoders) {
        const ms = await timed('decodeVolume', (enc, tw) => d.encodeDecodeVolume(enc, { stream: v.stream, output, timestampWrites: tw }));
        const gbps = floatBytes / (ms.median * 1e6);
        run.figure(SECTION, `whole volume ${v.key}, ${d.path} path: GB/s`, gbps, 'GB/s');
        rows.push([v.key, 'whole volume', `${d.path}${d.path === autoPath ? ' *' : ''}`, ms.median, gbps]);
        records.push({ volume: v.key, op: 'whole volume', path: d.path, floatBytes, ms, gbPerSecond: gbps });
        console.log(`  ${v.key} whole volume, ${d.path}: ${ms.median.toFixed(3)} ms, ${gbps.toFixed(1)} GB/s`);
      }
      const decoded = v.sha256 ? await readF32(device, output, 0, floatBytes / 4) : undefined;
      if (decoded && v.sha256) {
        const sha = createHash('sha256')
          .update(new Uint8Array(decoded.buffer, decoded.byteOffset, decoded.byteLength))
          .digest('hex');
        run.check(
          SECTION,
          `${v.key}: the GPU decode equals zfpy's`,
          sha === v.sha256,
          `SHA-256 ${sha.slice(0, 16)}... against mc.json's ${v.sha256.slice(0, 16)}...`,
        );
      }

      // the sharded pool: every chunk in a slot, the pool cut into at least 4 storage bindings
      const edge = run.plan.smoke ? 32 : 64;
      const { layout, chunks } = chunkStreams(v.bytes, info, edge);
      const maxShardBytes = Math.max(layout.chunkBytes + 4, Math.ceil(chunks.length / 4) * layout.chunkBytes + 4);
      const pool = ChunkedVolume.create(run.gpu, layout, { poolChunks: chunks.length, maxShardBytes });
      chunks.forEach((c, i) => pool.put(i, c));
      const blocks = chunks.length * pool.blocksPerChunk;
      const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
      const ids = device.createBuffer({ label: 'benchGpu.poolIds', size: blocks * 4, usage });
      device.queue.writeBuffer(
        ids,
        0,
        Uint32Array.from({ length: blocks }, (_, i) => i),
      );
      const count = device.createBuffer({ label: 'benchGpu.poolCount', size: 4, usage });
      device.queue.writeBuffer(count, 0, new Uint32Array([blocks]));
      const slots = device.createBuffer({ label: 'benchGpu.poolSlots', size: blocks * 256, usage });
      try {
        for (const d of decoders) {
          const ms = await timed('decodePool', (enc, tw) =>
            d.encodeDecodeBlocks(enc, {
              stream: pool,
              blockIds: ids,
              slotIds: ids,
              count: { buffer: count, offset: 0 },
              slots,
              timestampWrites: tw,
            }),
          );
          const gbps = (blocks * 256) / (ms.median * 1e6);
          const what = `sharded pool (${chunks.length} chunks of ${edge}^3, ${pool.shards.length} bindings)`;
          run.figure(SECTION, `${what} ${v.key}, ${d.path} path: GB/s`, gbps, 'GB/s');
          rows.push([v.key, what, `${d.path}${d.path === autoPath ? ' *' : ''}`, ms.median, gbps]);
          records.push({
            volume: v.key,
            op: 'sharded pool',
            chunks: chunks.length,
            shards: pool.shards.length,
            path: d.path,
            ms,
            gbPerSecond: gbps,
          });
          console.log(`  ${v.key} ${what}, ${d.path}: ${ms.median.toFixed(3)} ms, ${gbps.toFixed(1)} GB/s`);
        }
        if (decoded) {
          const got = await readF32(device, slots, 0, blocks * 64);
          const bad = comparePoolWithVolume(got, decoded, pool, layout);
          run.check(
            SECTION,
            `${v.key}: the sharded pool's blocks equal the whole decode`,
            bad === '',
            bad || `${blocks} blocks in ${pool.shards.length} bindings, bit for bit`,
          );
        }
      } finally {
        for (const b of [ids, count, slots, output]) b.destroy();
        pool.destroy();
      }
    }
  } finally {
    for (const v of volumes) v.stream.destroy();
    for (const d of decoders) d.destroy();
    timer.destroy();
  }
  run.table({
    title: `zfp decode, GB/s of float32 written (${timer.source}; median of ${run.plan.decodeRepeats} after a discarded first; * = the path 'auto' picks)`,
    header: ['volume', 'decode', 'path', 'median ms', 'GB/s'],
    rows,
  });
  return { autoPath, records };
}

/** '' when every slot holds its block of `volume` (x fastest), else where the first difference is. */
function comparePoolWithVolume(slots: Float32Array, volume: Float32Array, pool: ChunkedVolume, layout: ChunkLevelLayout): string {
  const [nx, ny] = layout.dims;
  const cb = layout.chunkEdge / 4;
  const per = pool.blocksPerChunk;
  const u = new Uint32Array(slots.buffer, slots.byteOffset, slots.length);
  const w = new Uint32Array(volume.buffer, volume.byteOffset, volume.length);
  for (const chunk of pool.residentChunks()) {
    const slot = pool.slotOfChunk(chunk)!;
    const [cx, cy, cz] = pool.chunkCoords(chunk);
    for (let l = 0; l < per; l++) {
      const lx = l % cb,
        ly = Math.floor(l / cb) % cb,
        lz = Math.floor(l / (cb * cb));
      const base = (slot * per + l) * 64;
      for (let i = 0; i < 64; i++) {
        const x = (cx * cb + lx) * 4 + (i & 3),
          y = (cy * cb + ly) * 4 + ((i >> 2) & 3),
          z = (cz * cb + lz) * 4 + (i >> 4);
        if (u[base + i] !== w[x + nx * (y + ny * z)]) return `chunk (${cx}, ${cy}, ${cz}) voxel (${x}, ${y}, ${z}) differs`;
      }
    }
  }
  return '';
}
