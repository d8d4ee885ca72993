// A fixed-rate zfp stream resident on the GPU, uploaded once.
//
// Layout: the payload is cut at block boundaries into shards, each its own
// GPUBuffer no larger than one storage binding (the adapter's
// maxStorageBufferBindingSize, and maxBufferSize). A shard holds the 32-bit
// words from the one containing its first block's first bit to the one
// containing its last block's last bit, plus one zero word, so neighbouring
// shards may repeat a word. Kernels find block b of shard s at bit
// (b - firstBlock) * bitsPerBlock + bitBase, bitBase < 32.
//
// The header is not stripped by re-aligning bits on upload: 96 bits are 3
// whole words, so cutting at a word boundary costs nothing, and the 148-bit
// header (zfp's 64-bit mode word) is absorbed by bitBase like any shard start
// inside a word. Kernels handle a bit offset anyway (every block with a rate
// that is not a multiple of 0.5 starts inside a word), so no shifting copy of
// the stream is needed and the file's bytes go to the GPU as they are.

import { formatDims } from '../core/naming.ts';
import { bufferLayout } from '../gpu/bindings.ts';
import { openZfpStream, type OpenZfpOptions, type ZfpStreamInfo } from './format.ts';

export interface ZfpShard {
  buffer: GPUBuffer;
  firstBlock: number;
  endBlock: number;
  /** Index of the buffer's first word in the whole stream (file bytes / 4). */
  firstWord: number;
  /** Words of the stream held (without the extra zero word). */
  wordCount: number;
  /** Bit of firstBlock in the buffer. */
  bitBase: number;
  /** Bind group 0 of the decoder kernels (stream words + StreamParams). */
  bindGroup: GPUBindGroup;
}

export interface ShardPlan {
  firstBlock: number;
  endBlock: number;
  firstWord: number;
  wordCount: number;
  bitBase: number;
}

/** Bytes of one StreamParams record (uniform), at 256-byte strides. */
const PARAMS_BYTES = 48;
const PARAMS_STRIDE = 256;

/** Bind group layout 0 of the decoder kernels (the device's, from the pipeline cache). */
export function streamBindGroupLayout(device: GPUDevice): GPUBindGroupLayout {
  return bufferLayout(device, 'ZfpGpuStream.layout', ['read', 'uniform']);
}

/**
 * The largest shard buffer the device allows (bytes, multiple of 4), at most
 * 4 GiB - 4 so word indices and in-shard bit offsets stay in the kernels'
 * 32-bit word index / 64-bit bit arithmetic.
 */
export function maxShardBytesFor(device: GPUDevice): number {
  const l = device.limits;
  return Math.floor(Math.min(l.maxStorageBufferBindingSize, l.maxBufferSize, 2 ** 32 - 4) / 4) * 4;
}

/**
 * Cuts blocks [0, blockCount) into shards of at most `maxShardBytes` (incl.
 * the extra word). `rowBlocks` > 1 keeps shard ends on multiples of it (the
 * encoder needs whole z rows of blocks); `maxBlocks` caps blocks per shard.
 */
export function planShards(
  info: Pick<ZfpStreamInfo, 'blockCount' | 'bitsPerBlock' | 'payloadBitOffset' | 'fileName' | 'dims'>,
  maxShardBytes: number,
  rowBlocks = 1,
  maxBlocks = Infinity,
): ShardPlan[] {
  const { blockCount, bitsPerBlock: bpb, payloadBitOffset: p0 } = info;
  const maxWords = Math.floor(maxShardBytes / 4) - 1;
  const plans: ShardPlan[] = [];
  let first = 0;
  while (first < blockCount) {
    const startBit = p0 + first * bpb;
    // the first shard starts at the file's first word, header included
    const firstWord = first === 0 ? 0 : Math.floor(startBit / 32);
    // largest end with ceil((p0 + end * bpb) / 32) - firstWord <= maxWords
    let end = Math.min(blockCount, Math.floor((32 * (firstWord + maxWords) - p0) / bpb), first + maxBlocks);
    if (rowBlocks > 1 && end < blockCount) end = first + Math.floor((end - first) / rowBlocks) * rowBlocks;
    if (end <= first) {
      throw new Error(
        `${info.fileName}: a ${rowBlocks > 1 ? 'row of blocks' : 'block'} of ${formatDims(info.dims)} at ${bpb} bits per block does not fit one storage binding of ${maxShardBytes} bytes`,
      );
    }
    const endWord = Math.ceil((p0 + end * bpb) / 32);
    plans.push({ firstBlock: first, endBlock: end, firstWord, wordCount: endWord - firstWord, bitBase: startBit - 32 * firstWord });
    first = end;
  }
  return plans;
}

export interface UploadOptions {
  /** Cap on the shard size (default: the device's binding limit); tests use small values. */
  maxShardBytes?: number;
  label?: string;
}

/**
 * Where the decoder finds blocks: a whole stream (ZfpGpuStream) or chunks in
 * a pool (ChunkedVolume, chunked-volume.ts). The isosurface pipeline reads
 * either through this one interface.
 */
export interface BlockSource {
  readonly device: GPUDevice;
  readonly info: Pick<ZfpStreamInfo, 'fileName' | 'dims' | 'blockGrid' | 'blockCount' | 'bitsPerBlock' | 'rate'>;
  /** Bind group 0 of the decoder kernels, one per piece no larger than a storage binding. */
  readonly shards: readonly { readonly bindGroup: GPUBindGroup; readonly firstBlock: number; readonly endBlock: number }[];
  /** 'stream': blocks back to back (stream_address.wgsl); 'pool': chunks through a page table (pool_address.wgsl). */
  readonly addressing: 'stream' | 'pool';
  readonly isDestroyed: boolean;
  /** Bytes of GPU memory held. */
  readonly byteSize: number;
}

/** A zfp stream in GPU memory; owns its buffers (destroy() frees them). */
export class ZfpGpuStream implements BlockSource {
  readonly addressing = 'stream';
  private destroyed = false;

  private constructor(
    readonly device: GPUDevice,
    readonly info: ZfpStreamInfo,
    readonly shards: readonly ZfpShard[],
    private readonly params: GPUBuffer,
  ) {}

  /** Bytes of GPU memory held. */
  get byteSize(): number {
    return this.shards.reduce((s, sh) => s + sh.buffer.size, 0) + this.params.size;
  }

  /** Uploads the file `bytes` (as validated by openZfpStream) once. */
  static upload(device: GPUDevice, info: ZfpStreamInfo, bytes: Uint8Array, opts: UploadOptions = {}): ZfpGpuStream {
    if (bytes.byteLength < info.requiredBytes)
      throw new Error(`${info.fileName}: ${bytes.byteLength} bytes given, the stream needs ${info.requiredBytes}`);
    const plans = planShards(info, opts.maxShardBytes ?? maxShardBytesFor(device));
    return ZfpGpuStream.create(device, info, plans, opts.label ?? 'ZfpGpuStream', (plan, mapped) => {
      const start = plan.firstWord * 4;
      const end = Math.min(bytes.byteLength, (plan.firstWord + plan.wordCount) * 4);
      mapped.set(bytes.subarray(start, end));
    });
  }

  /**
   * Creates zeroed shard buffers for `plans` (filled by `fill` when given,
   * through a mapped range); used by upload() and by the encoder.
   */
  static create(
    device: GPUDevice,
    info: ZfpStreamInfo,
    plans: readonly ShardPlan[],
    label: string,
    fill?: (plan: ShardPlan, mapped: Uint8Array) => void,
  ): ZfpGpuStream {
    const layout = streamBindGroupLayout(device);
    const params = device.createBuffer({
      label: `${label}.params`,
      size: PARAMS_STRIDE * (plans.length - 1) + PARAMS_BYTES,
      usage: GPUBufferUsage.UNIFORM,
      mappedAtCreation: true,
    });
    const shards: ZfpShard[] = [];
    try {
      const p = params.getMappedRange();
      plans.forEach((plan, i) => {
        const u = new Uint32Array(p, i * PARAMS_STRIDE, PARAMS_BYTES / 4);
        u.set([...info.dims, info.bitsPerBlock, ...info.blockGrid, info.blockCount, plan.firstBlock, plan.endBlock, plan.bitBase, 0]);
      });
      params.unmap();
      plans.forEach((plan, i) => {
        const buffer = device.createBuffer({
          label: `${label}.shard${i}`,
          size: (plan.wordCount + 1) * 4,
          usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC,
          mappedAtCreation: fill !== undefined,
        });
        shards.push({ ...plan, buffer, bindGroup: undefined as unknown as GPUBindGroup });
        if (fill) {
          fill(plan, new Uint8Array(buffer.getMappedRange()));
          buffer.unmap();
        }
        shards[i].bindGroup = device.createBindGroup({
          label: `${label}.shard${i}.bindGroup`,
          layout,
          entries: [
            { binding: 0, resource: { buffer } },
            { binding: 1, resource: { buffer: params, offset: i * PARAMS_STRIDE, size: PARAMS_BYTES } },
          ],
        });
      });
    } catch (e) {
      for (const s of shards) s.buffer.destroy();
      params.destroy();
      throw e;
    }
    return new ZfpGpuStream(device, info, shards, params);
  }

  /** Shard holding block b. */
  shardOf(block: number): number {
    let lo = 0,
      hi = this.shards.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (this.shards[mid].firstBlock <= block) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  get isDestroyed(): boolean {
    return this.destroyed;
  }

  destroy(): void {
    if (this.destroyed) return;
    this.destroyed = true;
    for (const s of this.shards) s.buffer.destroy();
    this.params.destroy();
  }

  /**
   * Reads the stream back as zfp's file bytes (header included when the
   * stream has one, zero padding to a 64-bit word). Waits for the GPU:
   * for the CLI, tests and downloads.
   */
  async readBytes(): Promise<Uint8Array> {
    const { device, info } = this;
    const out = new Uint8Array(info.paddedBytes);
    const largest = Math.max(...this.shards.map((s) => s.wordCount)) * 4;
    const staging = device.createBuffer({
      label: 'ZfpGpuStream.readBytes',
      size: largest,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    try {
      for (const s of this.shards) {
        const encoder = device.createCommandEncoder({ label: 'ZfpGpuStream.readBytes' });
        encoder.copyBufferToBuffer(s.buffer, 0, staging, 0, s.wordCount * 4);
        device.queue.submit([encoder.finish()]);
        await staging.mapAsync(GPUMapMode.READ, 0, s.wordCount * 4);
        const words = new Uint8Array(staging.getMappedRange(0, s.wordCount * 4));
        const at = s.firstWord * 4;
        const n = Math.min(words.byteLength, out.byteLength - at);
        // the first word may be shared with the previous shard: OR it in
        for (let i = 0; i < Math.min(4, n); i++) out[at + i] |= words[i];
        if (n > 4) out.set(words.subarray(4, n), at + 4);
        staging.unmap();
      }
    } finally {
      staging.destroy();
    }
    return out;
  }
}

/**
 * The one call the page and the CLI need: validates the file (throwing a
 * ZfpFormatError that names it, before any GPU allocation) and uploads it.
 */
export function loadZfpStream(
  device: GPUDevice,
  bytes: Uint8Array,
  fileName: string,
  opts: OpenZfpOptions & UploadOptions = {},
): ZfpGpuStream {
  const info = openZfpStream(bytes, fileName, opts);
  return ZfpGpuStream.upload(device, info, bytes, opts);
}
