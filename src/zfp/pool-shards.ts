// A chunk pool's pieces on the GPU: each shard is one buffer of slots no
// larger than a storage binding, with its bind group 0 for the decoder
// kernels (shaders/zfp/pool_address.wgsl): the pool's buffer, its
// StreamParams and PoolParams records (one uniform buffer for all shards),
// and the level's tables.
import { bufferLayout } from '../gpu/bindings.ts';
import type { ChunkLevelLayout } from './chunk-layout.ts';

const STREAM_PARAMS_BYTES = 48;
const POOL_PARAMS_BYTES = 48;
const PARAMS_STRIDE = 256;

/** One piece of a pool: slots [firstSlot, endSlot) in `buffer`. */
export interface PoolShard {
  buffer: GPUBuffer;
  firstSlot: number;
  endSlot: number;
  bindGroup: GPUBindGroup;
  firstBlock: number;
  endBlock: number;
}

/** Bind group layout 0 of the decoder kernels over a pool (pool_address.wgsl; the device's, from the pipeline cache). */
export function poolBindGroupLayout(device: GPUDevice): GPUBindGroupLayout {
  return bufferLayout(device, 'ChunkedVolume.layout', ['read', 'uniform', 'read', 'uniform']);
}

/** Bytes of the parameters of a pool of `shards` shards. */
export function poolParamsBytes(shards: number): number {
  return PARAMS_STRIDE * (2 * shards - 1) + POOL_PARAMS_BYTES;
}

/** What the parameters say of a pool's level (ChunkedVolume's fields). */
export interface PoolFacts {
  readonly device: GPUDevice;
  readonly layout: ChunkLevelLayout;
  readonly info: { blockGrid: [number, number, number]; blockCount: number; bitsPerBlock: number };
  readonly chunkBlocks: number;
  readonly headerBits: number;
  readonly chunkCount: number;
  readonly tables: GPUBuffer;
}

/** The parameters (one StreamParams and one PoolParams record per shard) and each shard's bind group. */
export function bindPoolShards(
  pool: PoolFacts,
  shards: ReadonlyArray<Omit<PoolShard, 'bindGroup'>>,
): { params: GPUBuffer; shards: PoolShard[] } {
  const { device } = pool;
  const { dims, chunkGrid, chunkBytes, name } = pool.layout;
  const { blockGrid, blockCount, bitsPerBlock } = pool.info;
  const params = device.createBuffer({
    label: `${name}.poolParams`,
    size: poolParamsBytes(shards.length),
    usage: GPUBufferUsage.UNIFORM,
    mappedAtCreation: true,
  });
  const mapped = params.getMappedRange();
  const poolLayout = poolBindGroupLayout(device);
  const made: PoolShard[] = shards.map((shard, i) => {
    // the level's block count is not used by the pool's kernels (blocks are named by pool id): clamped to a u32
    const count = Math.min(blockCount, 0xffffffff);
    new Uint32Array(mapped, 2 * i * PARAMS_STRIDE, STREAM_PARAMS_BYTES / 4).set([
      ...dims,
      bitsPerBlock,
      ...blockGrid,
      count,
      0,
      count,
      0,
      0,
    ]);
    new Uint32Array(mapped, (2 * i + 1) * PARAMS_STRIDE, POOL_PARAMS_BYTES / 4).set([
      ...chunkGrid,
      pool.chunkBlocks,
      chunkBytes / 4,
      pool.headerBits,
      shard.firstSlot,
      shard.endSlot,
      pool.chunkCount,
      0,
      0,
      0,
    ]);
    const bindGroup = device.createBindGroup({
      label: `${name}.pool${i}.bindGroup`,
      layout: poolLayout,
      entries: [
        { binding: 0, resource: { buffer: shard.buffer } },
        { binding: 1, resource: { buffer: params, offset: 2 * i * PARAMS_STRIDE, size: STREAM_PARAMS_BYTES } },
        { binding: 2, resource: { buffer: pool.tables } },
        { binding: 3, resource: { buffer: params, offset: (2 * i + 1) * PARAMS_STRIDE, size: POOL_PARAMS_BYTES } },
      ],
    });
    return { ...shard, bindGroup };
  });
  params.unmap();
  return { params, shards: made };
}
