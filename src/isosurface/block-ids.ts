// How the pipeline names blocks (shaders/isosurface/blocks_*.wgsl). A whole
// stream's blocks are named by their raster index; a chunk pool's by pool
// id, slot * B + the block's index in its chunk (B = (C/4)^3), so every
// per-block buffer of the pipeline is sized by what the pool holds, never by
// the level (a 16384^3 level has 2^36 blocks; a pool of 2000 chunks of 64^3
// has 8 M ids). The kernels see three functions (block_coords, block_at,
// group_block_id); a pool's need its level's tables (page table and slot
// table, one storage binding), in bind group 3 of every kernel that
// composes them (groups before it that the kernel does not use get an empty
// one).
import { bindGroup, bufferLayout } from '../gpu/bindings.ts';
import { bindGroupLayout } from '../gpu/pipeline-cache.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import { blockIdsSnippet } from './wgsl.ts';

/** The bind group index of a pool's block-id tables. */
const POOL_GROUP = 3;

export interface BlockIds {
  readonly kind: 'stream' | 'pool';
  /** The WGSL part the id-using kernels compose. */
  readonly part: WgslPart;
  /** How many ids there are: a stream's block count, or the pool's slots x blocks per chunk. What per-block buffers hold. */
  readonly count: number;
  /** The pool, for a pool's ids. */
  readonly pool?: ChunkedVolume;
  /** A kernel's bind group layouts: its own (groups 0 ...), and for a pool empty ones up to group 3, then the id tables. */
  layouts(own: readonly GPUBindGroupLayout[]): GPUBindGroupLayout[];
  /** Sets what layouts() added (for a pool: empty groups from `own`, and group 3). */
  bind(pass: GPUComputePassEncoder, own: number): void;
  destroy(): void;
}

/** The ids of `source`; a pool's ids are fixed by its capacity when this is made (a surface is made again when a pool is resized). */
export function blockIdsOf(device: GPUDevice, source: BlockSource): BlockIds {
  if (source.addressing !== 'pool') {
    return {
      kind: 'stream',
      part: blockIdsSnippet.stream,
      count: source.info.blockCount,
      layouts: (own) => [...own],
      bind: () => {},
      destroy: () => {},
    };
  }
  const pool = source as ChunkedVolume;
  const count = pool.poolChunks * pool.blocksPerChunk;
  if (count >= 2 ** 32)
    throw new RangeError(
      `${pool.layout.name}: a pool of ${pool.poolChunks} chunks has ${count} block ids, more than 32-bit ids hold; use a smaller budget or smaller chunks`,
    );
  const empty = bindGroupLayout(device, 'Isosurface.empty.layout', []);
  const emptyGroup = device.createBindGroup({ label: 'Isosurface.empty.bindGroup', layout: empty, entries: [] });
  const tablesLayout = bufferLayout(device, 'Isosurface.poolBlocks.layout', ['uniform', 'read']);
  const params = device.createBuffer({
    label: 'Isosurface.poolBlocks',
    size: 32,
    usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
  });
  device.queue.writeBuffer(params, 0, new Uint32Array([...pool.layout.chunkGrid, pool.chunkBlocks, pool.chunkCount, 0, 0, 0]));
  const tables = bindGroup(device, 'Isosurface.poolBlocks.bindGroup', tablesLayout, [params, pool.tables]);
  return {
    kind: 'pool',
    part: blockIdsSnippet.pool,
    count,
    pool,
    layouts: (own) => {
      const out = [...own];
      while (out.length < POOL_GROUP) out.push(empty);
      out.push(tablesLayout);
      return out;
    },
    bind: (pass, own) => {
      for (let g = own; g < POOL_GROUP; g++) pass.setBindGroup(g, emptyGroup);
      pass.setBindGroup(POOL_GROUP, tables);
    },
    destroy: () => params.destroy(),
  };
}
