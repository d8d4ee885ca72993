// TEMPORARY stand-in for src/isosurface's Isosurface while it is being
// written: decodes the whole stream once, meshes on the CPU. Same interface.
import type { GpuContext } from '../../gpu/device.ts';
import type { IsosurfaceDrawData, IsosurfaceStats, VolumeInfo } from '../../isosurface/types.ts';
import { marchingCubes } from '../../mc/serial-mc.ts';
import { ZfpDecoder } from '../../zfp/decoder.ts';
import type { ZfpGpuStream } from '../../zfp/gpu-stream.ts';
import { blocksOf, packTriangleSoup } from './cpu-surface.ts';

export class CpuIsosurface {
  drawData: IsosurfaceDrawData;
  private statsListeners: ((s: IsosurfaceStats) => void)[] = [];
  private errorListeners: ((e: Error) => void)[] = [];
  private pending: number | undefined;
  private running = false;
  private vertexCount = 0;

  private constructor(
    private readonly device: GPUDevice,
    readonly info: VolumeInfo,
    private readonly values: Float32Array,
    private readonly ranges: Float32Array,
  ) {
    const { blockCount } = info;
    const mk = (label: string, size: number, usage: number) => device.createBuffer({ label, size: Math.max(16, size), usage: usage | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC });
    const slotData = mk('cpu.slots', blockCount * 256, GPUBufferUsage.STORAGE);
    device.queue.writeBuffer(slotData, 0, blocksOf(values, info.dims) as Float32Array<ArrayBuffer>);
    const blockToSlot = mk('cpu.blockToSlot', blockCount * 4, GPUBufferUsage.STORAGE);
    device.queue.writeBuffer(blockToSlot, 0, Uint32Array.from({ length: blockCount }, (_, i) => i));
    this.drawData = {
      shards: [{ vertices: mk('cpu.vertices', 16, GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE), drawArgs: mk('cpu.args', 16, GPUBufferUsage.INDIRECT), drawArgsOffset: 0 }],
      info,
      slotData,
      blockToSlot,
      version: 0,
    };
  }

  static async create(gpu: GpuContext, stream: ZfpGpuStream): Promise<CpuIsosurface> {
    const decoder = await ZfpDecoder.create(gpu.device);
    const values = (await decoder.readVolume(stream))!;
    const rb = decoder.computeBlockRanges(stream);
    const staging = gpu.device.createBuffer({ size: rb.size, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const enc = gpu.device.createCommandEncoder();
    enc.copyBufferToBuffer(rb, 0, staging, 0, rb.size);
    gpu.device.queue.submit([enc.finish()]);
    await staging.mapAsync(GPUMapMode.READ);
    const ranges = new Float32Array(staging.getMappedRange().slice(0));
    staging.destroy();
    rb.destroy();
    decoder.destroy();
    let lo = Infinity, hi = -Infinity;
    for (let i = 0; i < ranges.length; i += 2) {
      lo = Math.min(lo, ranges[i]);
      hi = Math.max(hi, ranges[i + 1]);
    }
    const { dims, blockGrid, blockCount } = stream.info;
    return new CpuIsosurface(gpu.device, { dims, blockGrid, blockCount, valueRange: [lo, hi] }, values, ranges);
  }

  onStats(l: (s: IsosurfaceStats) => void): void {
    this.statsListeners.push(l);
  }
  onError(l: (e: Error) => void): void {
    this.errorListeners.push(l);
  }

  setIsovalue(iso: number): void {
    this.pending = iso;
    if (!this.running) void this.pump();
  }

  private async pump(): Promise<void> {
    this.running = true;
    while (this.pending !== undefined) {
      const iso = this.pending;
      this.pending = undefined;
      await new Promise((r) => setTimeout(r, 0));
      try {
        const s = await this.compute(iso);
        for (const l of this.statsListeners) l(s);
      } catch (e) {
        for (const l of this.errorListeners) l(e as Error);
      }
    }
    this.running = false;
  }

  async compute(iso: number): Promise<IsosurfaceStats> {
    const t0 = performance.now();
    const mc = marchingCubes(this.values, this.info.dims, iso);
    const packed = packTriangleSoup(mc.positions, this.info.dims);
    const shard = this.drawData.shards[0];
    if (shard.vertices.size < packed.byteLength) {
      shard.vertices.destroy();
      shard.vertices = this.device.createBuffer({ label: 'cpu.vertices', size: packed.byteLength * 1.5 + 16, usage: GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC });
    }
    if (packed.byteLength) this.device.queue.writeBuffer(shard.vertices, 0, packed as Uint32Array<ArrayBuffer>);
    this.device.queue.writeBuffer(shard.drawArgs, 0, new Uint32Array([mc.triangleCount * 3, 1, 0, 0]));
    this.vertexCount = mc.triangleCount * 3;
    const f = Math.fround(iso);
    let active = 0;
    for (let i = 0; i < this.ranges.length; i += 2) if (this.ranges[i] <= f && f <= this.ranges[i + 1]) active++;
    const occ = new Set<number>();
    for (let i = 1; i < packed.length; i += 2) occ.add(packed[i]);
    const ms = performance.now() - t0;
    return {
      isovalue: iso, activeBlocks: active, newBlocks: 0, occupiedBlocks: occ.size, hitRate: 1, vertices: this.vertexCount, triangles: mc.triangleCount,
      cacheSlots: this.info.blockCount, cacheSlotsUsed: this.info.blockCount, cacheBytes: this.info.blockCount * 260, vertexBytes: shard.vertices.size,
      gpuMs: ms, stages: [{ label: 'cpu-mc', ms }], timingSource: 'queue-wall-time', grew: false,
    };
  }

  resetCache(): void {}
  setMemoryBudget(_bytes: number): void {}

  async readVertices(): Promise<Uint32Array> {
    const shard = this.drawData.shards[0];
    const size = this.vertexCount * 8;
    if (size === 0) return new Uint32Array(0);
    const staging = this.device.createBuffer({ size, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const enc = this.device.createCommandEncoder();
    enc.copyBufferToBuffer(shard.vertices, 0, staging, 0, size);
    this.device.queue.submit([enc.finish()]);
    await staging.mapAsync(GPUMapMode.READ);
    const out = new Uint32Array(staging.getMappedRange().slice(0));
    staging.destroy();
    return out;
  }

  async readBlockRanges(): Promise<Float32Array> {
    return this.ranges.slice();
  }

  destroy(): void {
    for (const s of this.drawData.shards) {
      s.vertices.destroy();
      s.drawArgs.destroy();
    }
    this.drawData.slotData.destroy();
    this.drawData.blockToSlot.destroy();
  }
}
