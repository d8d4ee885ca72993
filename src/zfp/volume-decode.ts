// Whole-volume decode of a ZfpGpuStream into a float32 volume (x fastest), in
// slabs of block rows, once per stream shard. Two kernel families, chosen per
// adapter with the block-list decode's (ZfpDecoder `path`):
//  - emulator path, decode_volume.wgsl: one invocation per block (workgroups
//    of 64) writes its block's voxels itself;
//  - GPU path, decode_volume_tiled.wgsl: a workgroup of 32 decodes 32 blocks
//    along x of one block row into workgroup memory, then writes the tile's
//    voxel lines with consecutive invocations on consecutive voxels.
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { binding, inPass, refSize, type ComputeTarget, type GpuBufferRef } from '../gpu/buffer-ref.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { UniformSlots } from '../gpu/uniform-slots.ts';
import type { PrimitivePath } from '../primitives/dispatch-records.ts';
import { maxShardBytesFor, type ZfpGpuStream } from './gpu-stream.ts';
import { zfpWgsl } from './wgsl.ts';

export interface DecodeVolumeArgs {
  stream: ZfpGpuStream;
  /** f32 voxels x fastest; holds z planes [4 * zBlockBegin, min(4 * zBlockEnd, nz)). STORAGE usage. */
  output: GpuBufferRef;
  /** Block rows (z) to decode; default: all. */
  zBlockBegin?: number;
  zBlockEnd?: number;
  timestampWrites?: GPUComputePassTimestampWrites;
}

/** Blocks along x per workgroup of the GPU-path volume decode (TILE in decode_volume_tiled.wgsl). */
export const VOLUME_TILE_BLOCKS = 32;

/** Bytes of z block rows [zBlockBegin, zBlockEnd) decoded as float32. */
export function volumeBytes(stream: ZfpGpuStream, zBlockBegin = 0, zBlockEnd = stream.info.blockGrid[2]): number {
  const [nx, ny, nz] = stream.info.dims;
  return nx * ny * (Math.min(4 * zBlockEnd, nz) - 4 * zBlockBegin) * 4;
}

/** Block-row slabs [z0, z1) whose float32 output fits one storage binding of `maxBytes`. */
export function volumeSlabs(stream: ZfpGpuStream, maxBytes = maxShardBytesFor(stream.device)): [number, number][] {
  const [nx, ny] = stream.info.dims;
  const bz = stream.info.blockGrid[2];
  const rowBytes = nx * ny * 4 * 4;
  const rows = Math.floor(maxBytes / rowBytes);
  if (rows < 1)
    throw new Error(
      `${stream.info.fileName}: one row of blocks (${rowBytes} bytes as float32) does not fit one storage binding of ${maxBytes} bytes`,
    );
  const slabs: [number, number][] = [];
  for (let z = 0; z < bz; z += rows) slabs.push([z, Math.min(bz, z + rows)]);
  return slabs;
}

/** The GPU path's tile (workgroup) of block b: its block row, then its 32-block run along x. */
function tileOf(b: number, bx: number, tilesX: number): number {
  return Math.floor(b / bx) * tilesX + Math.floor((b % bx) / VOLUME_TILE_BLOCKS);
}

interface ShardWork {
  shard: number;
  group: GPUBindGroup;
  workgroups: number;
}

export class VolumeDecodeKernel {
  private readonly groups = new BindGroupCache();
  private readonly words = new Uint32Array(4);
  // reused by every encode (no allocation per call once the shards have been seen)
  private readonly work: ShardWork[] = [];
  private workCount = 0;

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
    private readonly uniforms: UniformSlots,
    private readonly maxWorkgroups: number,
    readonly path: PrimitivePath,
  ) {}

  static async create(
    device: GPUDevice,
    path: PrimitivePath,
    streamLayout: GPUBindGroupLayout,
    uniforms: UniformSlots,
    maxWorkgroups: number,
  ): Promise<VolumeDecodeKernel> {
    const layout = bindGroupLayout(device, 'ZfpDecoder.decodeVolume.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
    ]);
    const parts = path === 'gpu' ? zfpWgsl.decodeVolumeTiled : zfpWgsl.decodeVolume;
    const pipeline = await createComputePipeline(device, `ZfpDecoder.decodeVolume.${path}`, parts, 'decode_volume', {
      layout: [streamLayout, layout],
    });
    return new VolumeDecodeKernel(device, pipeline, uniforms, maxWorkgroups, path);
  }

  /** Records the decode of z block rows [zBlockBegin, zBlockEnd) into a float32 volume (x fastest). */
  encode(target: ComputeTarget, a: DecodeVolumeArgs): void {
    const { info } = a.stream;
    const [bx, by, bz] = info.blockGrid;
    const z0 = a.zBlockBegin ?? 0;
    const z1 = a.zBlockEnd ?? bz;
    if (!(Number.isInteger(z0) && Number.isInteger(z1) && z0 >= 0 && z0 < z1 && z1 <= bz)) {
      throw new Error(`ZfpDecoder: block rows [${z0}, ${z1}) are not inside [0, ${bz})`);
    }
    const need = volumeBytes(a.stream, z0, z1);
    if (refSize(a.output) < need) throw new Error(`ZfpDecoder: the output has ${refSize(a.output)} bytes, ${need} are needed`);
    const first = z0 * bx * by;
    const end = z1 * bx * by;
    const tilesX = Math.ceil(bx / VOLUME_TILE_BLOCKS);
    const tiled = this.path === 'gpu';
    let n = 0;
    for (let s = 0; s < a.stream.shards.length; s++) {
      const shard = a.stream.shards[s];
      const lo = Math.max(first, shard.firstBlock);
      const hi = Math.min(end, shard.endBlock);
      if (lo >= hi) continue;
      const firstTile = tiled ? tileOf(lo, bx, tilesX) : 0;
      this.words.set([lo, hi, 4 * z0, firstTile]);
      const params = this.uniforms.get(this.words);
      const group = this.groups
        .ref(a.output)
        .key(params.buffer)
        .key(params.offset!)
        .get(() =>
          this.device.createBindGroup({
            label: 'ZfpDecoder.decodeVolume.bindGroup',
            layout: this.pipeline.getBindGroupLayout(1),
            entries: [
              { binding: 0, resource: params },
              { binding: 1, resource: binding(a.output) },
            ],
          }),
        );
      if (n === this.work.length) this.work.push({ shard: 0, group, workgroups: 0 });
      const w = this.work[n++];
      w.shard = s;
      w.group = group;
      w.workgroups = tiled ? tileOf(hi - 1, bx, tilesX) - firstTile + 1 : Math.ceil((hi - lo) / 64);
    }
    this.workCount = n;
    inPass(
      target,
      'ZfpDecoder.decodeVolume',
      (pass) => {
        pass.setPipeline(this.pipeline);
        for (let i = 0; i < this.workCount; i++) {
          const w = this.work[i];
          pass.setBindGroup(0, a.stream.shards[w.shard].bindGroup);
          pass.setBindGroup(1, w.group);
          dispatchWorkgroups(pass, w.workgroups, this.maxWorkgroups);
        }
      },
      a.timestampWrites,
    );
  }

  destroy(): void {
    this.groups.clear();
  }
}
