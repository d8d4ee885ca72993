// The vertex output: the triangle soup in the compressed format (8 bytes per
// vertex) and its normals (4 bytes per vertex, a parallel buffer), split into shards of at most one storage binding each. Vertex i
// lives in shard floor(i / perShard) at i mod perShard. Each shard has a
// drawIndirect record and a shard_info record (plan.wgsl), both written on
// the GPU: the draw count of shard k is clamp(total - k * perShard, 0, perShard).
import { DRAW_ARGS_BYTES, NORMAL_BYTES, SHARD_RECORD_BINDING, SHARD_RECORD_BYTES, VERTEX_BYTES } from './layout.ts';
import type { VertexShard } from './types.ts';

export interface ShardBuffer {
  vertices: GPUBuffer;
  /** One octahedral normal (u32) per vertex, written with the vertices. */
  normals: GPUBuffer;
  /** Global index of the shard's first vertex. */
  base: number;
  /** Vertices the shard holds. */
  size: number;
}

export class VertexShards {
  private list: ShardBuffer[] = [];
  private drawArgsBuffer!: GPUBuffer;
  private shardInfoBuffer!: GPUBuffer;
  private capacityValue = 0;

  /**
   * @param perShard vertices per shard (maxVertexBindingBytes / 8)
   */
  constructor(
    private readonly device: GPUDevice,
    readonly perShard: number,
    capacity: number,
  ) {
    this.allocate(capacity);
  }

  get capacity(): number {
    return this.capacityValue;
  }

  get shards(): readonly ShardBuffer[] {
    return this.list;
  }

  /** drawIndirect arguments, 16 bytes per shard. */
  get drawArgs(): GPUBuffer {
    return this.drawArgsBuffer;
  }

  /** Per shard a 256-byte record: first occupied entry, count, base, dispatch args (at byte 16). */
  get shardInfo(): GPUBuffer {
    return this.shardInfoBuffer;
  }

  /** Binding of shard k's record (what the vertex pass reads). */
  shardRecord(k: number): GPUBufferBinding {
    return { buffer: this.shardInfoBuffer, offset: k * SHARD_RECORD_BYTES, size: SHARD_RECORD_BINDING };
  }

  /** Byte offset of shard k's vertex-pass dispatch arguments in shardInfo. */
  static dispatchArgsOffset(k: number): number {
    return k * SHARD_RECORD_BYTES + 16;
  }

  /** What the renderer binds (types.ts VertexShard). */
  get drawShards(): VertexShard[] {
    return this.list.map((s, k) => ({
      vertices: s.vertices,
      normals: s.normals,
      drawArgs: this.drawArgsBuffer,
      drawArgsOffset: k * DRAW_ARGS_BYTES,
    }));
  }

  get byteSize(): number {
    return this.list.reduce((n, s) => n + s.vertices.size + s.normals.size, 0) + this.drawArgsBuffer.size + this.shardInfoBuffer.size;
  }

  /** Bytes the buffers take at `capacity` vertices. */
  static bytesFor(capacity: number, perShard: number): number {
    const shards = Math.max(1, Math.ceil(capacity / perShard));
    return Math.max(capacity, 1) * (VERTEX_BYTES + NORMAL_BYTES) + shards * (DRAW_ARGS_BYTES + SHARD_RECORD_BYTES);
  }

  private allocate(capacity: number): void {
    const d = this.device;
    const count = Math.max(1, Math.ceil(capacity / this.perShard));
    this.list = [];
    for (let k = 0; k < count; k++) {
      const size = Math.max(1, Math.min(this.perShard, capacity - k * this.perShard));
      this.list.push({
        vertices: d.createBuffer({
          label: `Isosurface.vertices${k}`,
          size: size * VERTEX_BYTES,
          usage: GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
        }),
        normals: d.createBuffer({
          label: `Isosurface.normals${k}`,
          size: size * NORMAL_BYTES,
          usage: GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
        }),
        base: k * this.perShard,
        size,
      });
    }
    // [0, 1, 0, 0] per shard: nothing drawn until a surface is computed.
    this.drawArgsBuffer = d.createBuffer({
      label: 'Isosurface.drawArgs',
      size: count * DRAW_ARGS_BYTES,
      usage: GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
      mappedAtCreation: true,
    });
    const args = new Uint32Array(this.drawArgsBuffer.getMappedRange());
    for (let k = 0; k < count; k++) args[4 * k + 1] = 1;
    this.drawArgsBuffer.unmap();
    this.shardInfoBuffer = d.createBuffer({
      label: 'Isosurface.shardInfo',
      size: count * SHARD_RECORD_BYTES,
      usage: GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
    this.capacityValue = capacity;
  }

  private destroyBuffers(): void {
    for (const s of this.list) {
      s.vertices.destroy();
      s.normals.destroy();
    }
    this.drawArgsBuffer.destroy();
    this.shardInfoBuffer.destroy();
  }

  /**
   * Replaces the buffers by ones holding `capacity` vertices (nothing is
   * copied: the caller recomputes the surface). Call between submissions.
   */
  resize(capacity: number): void {
    this.destroyBuffers();
    this.allocate(capacity);
  }

  destroy(): void {
    this.destroyBuffers();
    this.list = [];
  }
}
