// The volume's value at a point (a picked point of a surface): the trilinear
// interpolant of the decoded voxels of the cell holding it, as the surface
// is made from them. The cell's 8 corners lie in at most 8 blocks, decoded
// on the GPU from the stream as the cache decodes them (ZfpDecoder
// .encodeDecodeBlocks) into a small buffer of its own and read back: one
// round trip per pick, nothing allocated per call once made. The source is a
// whole stream (blocks named by their raster index) or a level's pool of
// chunks (a store: blocks named by slot, chunkBlockId; a block whose chunk
// is not resident has no value there).
import { perDevice } from '../gpu/per-device.ts';
import { ZfpDecoder } from './decoder.ts';
import type { ChunkedVolume } from './chunked-volume.ts';
import type { BlockSource } from './gpu-stream.ts';

const MAX_BLOCKS = 8;

export class VolumeProbe {
  private readonly blockIds: GPUBuffer;
  private readonly slotIds: GPUBuffer;
  private readonly count: GPUBuffer;
  private readonly slots: GPUBuffer;
  private readonly readback: GPUBuffer;
  /** One probe at a time (the readback buffer is shared). */
  private queue: Promise<unknown> = Promise.resolve();

  private constructor(
    private readonly device: GPUDevice,
    private readonly decoder: ZfpDecoder,
  ) {
    const make = (label: string, size: number, usage: number) => device.createBuffer({ label: `VolumeProbe.${label}`, size, usage });
    const list = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
    this.blockIds = make('blockIds', 4 * MAX_BLOCKS, list);
    this.slotIds = make('slotIds', 4 * MAX_BLOCKS, list);
    this.count = make('count', 16, list);
    this.slots = make('slots', 4 * 64 * MAX_BLOCKS, list);
    this.readback = make('readback', 4 * 64 * MAX_BLOCKS, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
    device.queue.writeBuffer(
      this.slotIds,
      0,
      Uint32Array.from({ length: MAX_BLOCKS }, (_, i) => i),
    );
  }

  static async create(device: GPUDevice): Promise<VolumeProbe> {
    return new VolumeProbe(device, await ZfpDecoder.create(device));
  }

  /**
   * The trilinear value at `p` (voxel index coordinates, voxel (i, j, k) at
   * (i, j, k)) of the source's decoded volume; a point outside the volume
   * is moved onto its nearest cell. `idOf`: the decoder's name of a block
   * given its raster index (a pool: chunkBlockId), undefined when it cannot
   * be decoded; then the value is null.
   */
  sample(
    stream: BlockSource,
    p: readonly [number, number, number],
    idOf: (block: number) => number | undefined = (b) => b,
  ): Promise<number | null> {
    const run = () => this.#sample(stream, p, idOf);
    const next = this.queue.then(run, run);
    this.queue = next.catch(() => undefined);
    return next;
  }

  async #sample(
    stream: BlockSource,
    p: readonly [number, number, number],
    idOf: (block: number) => number | undefined,
  ): Promise<number | null> {
    const { dims, blockGrid } = stream.info;
    if (!p.every(Number.isFinite)) throw new RangeError(`VolumeProbe: point ${p.join(', ')} is not finite`);
    // the cell: its lower corner within [0, n - 2] (a 1-voxel axis: the voxel itself), the fraction within [0, 1]
    const lower = [0, 1, 2].map((a) => Math.max(0, Math.min(Math.max(0, dims[a] - 2), Math.floor(p[a]))));
    const frac = [0, 1, 2].map((a) => (dims[a] < 2 ? 0 : Math.min(1, Math.max(0, p[a] - lower[a]))));
    const corners: [number, number, number][] = [];
    for (let k = 0; k < 8; k++) {
      corners.push([0, 1, 2].map((a) => Math.min(dims[a] - 1, lower[a] + ((k >> a) & 1))) as [number, number, number]);
    }
    const blockOf = (c: readonly number[]) => (c[0] >> 2) + blockGrid[0] * ((c[1] >> 2) + blockGrid[1] * (c[2] >> 2));
    const blocks = [...new Set(corners.map(blockOf))];
    const ids = blocks.map(idOf);
    if (ids.some((id) => id === undefined)) return null;
    const { device } = this;
    device.queue.writeBuffer(this.blockIds, 0, Uint32Array.from(ids as number[]));
    device.queue.writeBuffer(this.count, 0, Uint32Array.of(blocks.length));
    const encoder = device.createCommandEncoder({ label: 'VolumeProbe' });
    this.decoder.encodeDecodeBlocks(encoder, {
      stream,
      blockIds: this.blockIds,
      slotIds: this.slotIds,
      count: { buffer: this.count, offset: 0 },
      slots: this.slots,
    });
    encoder.copyBufferToBuffer(this.slots, 0, this.readback, 0, 4 * 64 * blocks.length);
    device.queue.submit([encoder.finish()]);
    await this.readback.mapAsync(GPUMapMode.READ, 0, 4 * 64 * blocks.length);
    const values = new Float32Array(this.readback.getMappedRange(0, 4 * 64 * blocks.length).slice(0));
    this.readback.unmap();
    const at = (c: readonly number[]) => values[64 * blocks.indexOf(blockOf(c)) + (c[0] & 3) + 4 * (c[1] & 3) + 16 * (c[2] & 3)];
    let v = 0;
    for (let k = 0; k < 8; k++) {
      let w = 1;
      for (let a = 0; a < 3; a++) w *= (k >> a) & 1 ? frac[a] : 1 - frac[a];
      v += w * at(corners[k]);
    }
    return v;
  }

  destroy(): void {
    for (const b of [this.blockIds, this.slotIds, this.count, this.slots, this.readback]) b.destroy();
    this.decoder.destroy();
  }
}

/**
 * A pool's name for block `block` (raster index over the level's block
 * grid): its chunk's slot times the blocks per chunk plus its index within
 * the chunk (shaders/zfp/pool_address.wgsl); undefined when the chunk is
 * not resident.
 */
export function chunkBlockId(pool: ChunkedVolume, block: number): number | undefined {
  const { chunk, local } = chunkOfBlock(pool, block);
  const slot = pool.slotOfChunk(chunk);
  return slot === undefined ? undefined : slot * pool.blocksPerChunk + local;
}

/** The chunk holding block `block` (raster index over the level's block grid), and the block's index within it (raster, x fastest). */
export function chunkOfBlock(pool: Pick<ChunkedVolume, 'layout' | 'info'>, block: number): { chunk: number; local: number } {
  const { chunkGrid, chunkEdge } = pool.layout;
  const grid = pool.info.blockGrid;
  const b = [block % grid[0], Math.floor(block / grid[0]) % grid[1], Math.floor(block / (grid[0] * grid[1]))];
  const per = chunkEdge / 4;
  const c = b.map((x) => Math.floor(x / per));
  return {
    chunk: c[0] + chunkGrid[0] * (c[1] + chunkGrid[1] * c[2]),
    local: (b[0] % per) + per * ((b[1] % per) + per * (b[2] % per)),
  };
}

/** The probe of a device, made on first use. */
export const probeFor = perDevice((device) => VolumeProbe.create(device));
