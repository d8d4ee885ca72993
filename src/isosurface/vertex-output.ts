// The surface output, welded: one vertex per cut edge (12 bytes: the
// compressed position and its normal, interleaved) in one vertex buffer, and
// the triangles as u32 indices into it, split into index shards of at most
// one storage binding each. Index i lives in shard floor(i / perShard) at
// i mod perShard. Each shard has a drawIndexedIndirect record and a
// shard_info record (plan.wgsl), both written on the GPU: the index count of
// shard k is clamp(total - k * perShard, 0, perShard).
import { readU32 } from '../gpu/buffers.ts';
import { DRAW_ARGS_BYTES, INDEX_BYTES, SHARD_RECORD_BINDING, SHARD_RECORD_BYTES, VERTEX_BYTES } from './layout.ts';
import type { IndexShard, SurfaceMesh } from './types.ts';

/**
 * A welded surface read back as an indexed mesh (CLI, exports; waits for the
 * GPU): `welded` vertices of `vertices`, then each index shard's first
 * `count` indices; every index is checked against the vertices read. The
 * surface's own buffers (pipeline.ts) or its drawn copy (snapshot.ts).
 */
export async function readWeldedMesh(
  device: GPUDevice,
  vertices: GPUBuffer | null,
  welded: number,
  shards: readonly { indices: GPUBuffer; count: number }[],
  dims: readonly [number, number, number],
): Promise<SurfaceMesh> {
  const v = vertices && welded > 0 ? await readU32(device, vertices, 0, (VERTEX_BYTES / 4) * welded) : new Uint32Array(0);
  const indices = new Uint32Array(shards.reduce((a, s) => a + s.count, 0));
  let at = 0;
  for (const s of shards) {
    if (s.count === 0) continue;
    indices.set(await readU32(device, s.indices, 0, s.count), at);
    at += s.count;
  }
  for (const i of indices) {
    if (i >= welded) throw new Error(`Isosurface: index ${i} outside the ${welded} vertices of the surface`);
  }
  return { vertices: v, indices, dims: [...dims] };
}

export interface ShardBuffer {
  indices: GPUBuffer;
  /** Global position of the shard's first index. */
  base: number;
  /** Indices the shard holds. */
  size: number;
}

export class SurfaceOutput {
  private list: ShardBuffer[] = [];
  private vertexBuffer!: GPUBuffer;
  private drawArgsBuffer!: GPUBuffer;
  private shardInfoBuffer!: GPUBuffer;
  private capacityValue = 0;
  private weldedValue = 0;

  /**
   * @param perShard indices per shard (a storage binding / 4)
   * @param capacity indices (triangle corners) the shards hold together
   * @param welded vertices the vertex buffer holds (at most one storage binding)
   */
  constructor(
    private readonly device: GPUDevice,
    readonly perShard: number,
    capacity: number,
    welded: number,
  ) {
    this.allocate(capacity, welded);
  }

  /** Indices (triangle corners) the shards hold. */
  get capacity(): number {
    return this.capacityValue;
  }

  /** Welded vertices the vertex buffer holds. */
  get weldedCapacity(): number {
    return this.weldedValue;
  }

  get shards(): readonly ShardBuffer[] {
    return this.list;
  }

  /** The welded vertices: per vertex 3 u32 (packed position, block id, normal). */
  get vertices(): GPUBuffer {
    return this.vertexBuffer;
  }

  /** drawIndexedIndirect arguments, 20 bytes per shard. */
  get drawArgs(): GPUBuffer {
    return this.drawArgsBuffer;
  }

  /** Per shard a 256-byte record: first emitting cell, count, base, dispatch args (at byte 16). */
  get shardInfo(): GPUBuffer {
    return this.shardInfoBuffer;
  }

  /** Binding of shard k's record (a uniform of the vertex pass). */
  shardRecord(k: number): GPUBufferBinding {
    return { buffer: this.shardInfoBuffer, offset: k * SHARD_RECORD_BYTES, size: SHARD_RECORD_BINDING };
  }

  /** Byte offset of shard k's vertex-pass dispatch arguments in shardInfo. */
  static dispatchArgsOffset(k: number): number {
    return k * SHARD_RECORD_BYTES + 16;
  }

  /** What the renderer binds (types.ts IndexShard). */
  get drawShards(): IndexShard[] {
    return this.list.map((s, k) => ({ indices: s.indices, drawArgs: this.drawArgsBuffer, drawArgsOffset: k * DRAW_ARGS_BYTES }));
  }

  get byteSize(): number {
    return (
      this.list.reduce((n, s) => n + s.indices.size, 0) + this.vertexBuffer.size + this.drawArgsBuffer.size + this.shardInfoBuffer.size
    );
  }

  /** Bytes the buffers take at `capacity` indices and `welded` vertices. */
  static bytesFor(capacity: number, welded: number, perShard: number): number {
    const shards = Math.max(1, Math.ceil(capacity / perShard));
    return Math.max(capacity, 1) * INDEX_BYTES + Math.max(welded, 1) * VERTEX_BYTES + shards * (DRAW_ARGS_BYTES + SHARD_RECORD_BYTES);
  }

  private createVertexBuffer(welded: number): GPUBuffer {
    return this.device.createBuffer({
      label: 'Isosurface.vertices',
      size: Math.max(1, welded) * VERTEX_BYTES,
      usage: GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
  }

  private allocate(capacity: number, welded: number): void {
    const d = this.device;
    const count = Math.max(1, Math.ceil(capacity / this.perShard));
    this.list = [];
    for (let k = 0; k < count; k++) {
      const size = Math.max(1, Math.min(this.perShard, capacity - k * this.perShard));
      this.list.push({
        indices: d.createBuffer({
          label: `Isosurface.indices${k}`,
          size: size * INDEX_BYTES,
          usage: GPUBufferUsage.INDEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
        }),
        base: k * this.perShard,
        size,
      });
    }
    this.vertexBuffer = this.createVertexBuffer(welded);
    // [0, 1, 0, 0, 0] per shard: nothing drawn until a surface is computed.
    this.drawArgsBuffer = d.createBuffer({
      label: 'Isosurface.drawArgs',
      size: count * DRAW_ARGS_BYTES,
      usage: GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
      mappedAtCreation: true,
    });
    const args = new Uint32Array(this.drawArgsBuffer.getMappedRange());
    for (let k = 0; k < count; k++) args[(DRAW_ARGS_BYTES / 4) * k + 1] = 1;
    this.drawArgsBuffer.unmap();
    this.shardInfoBuffer = d.createBuffer({
      label: 'Isosurface.shardInfo',
      size: count * SHARD_RECORD_BYTES,
      usage: GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE | GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_SRC,
    });
    this.capacityValue = capacity;
    this.weldedValue = Math.max(1, welded);
  }

  private destroyBuffers(): void {
    for (const s of this.list) s.indices.destroy();
    this.vertexBuffer.destroy();
    this.drawArgsBuffer.destroy();
    this.shardInfoBuffer.destroy();
  }

  /**
   * Replaces the buffers by ones holding `capacity` indices and `welded`
   * vertices (nothing is copied: the caller recomputes the surface). Call
   * between submissions.
   */
  resize(capacity: number, welded: number): void {
    this.destroyBuffers();
    this.allocate(capacity, welded);
  }

  /** Replaces only the vertex buffer, by one holding `welded` vertices (the index shards stay). Call between submissions. */
  resizeVertices(welded: number): void {
    this.vertexBuffer.destroy();
    this.vertexBuffer = this.createVertexBuffer(welded);
    this.weldedValue = Math.max(1, welded);
  }

  destroy(): void {
    this.destroyBuffers();
    this.list = [];
  }
}
