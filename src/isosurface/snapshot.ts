// A copy of a computed surface that is drawn while the surface it came from
// computes the next one: what makes a refinement step a snapshot (a view
// stream computes each level of a step in place, one after the other, and
// shows them together; the frames between draw the copies of the step
// before, whole). Copied on the GPU (copyBufferToBuffer, in queue order
// after the computation): the welded vertices the surface has, each index
// shard's indices, and the draw arguments, so the copy draws exactly what
// the surface drew. Its buffers are the surface's size, not its capacity;
// they are kept while a later copy fits (and is at least half their size)
// and made again when it does not.
import { DRAW_ARGS_BYTES, INDEX_BYTES, VERTEX_BYTES } from './layout.ts';
import type { IsosurfaceDrawData, SurfaceMesh } from './types.ts';
import { readWeldedMesh, type SurfaceOutput } from './vertex-output.ts';

/** What a surface holds: its welded vertices and its indices (IsosurfaceStats.vertices, .indices). */
export interface SurfaceCounts {
  vertices: number;
  indices: number;
}

export class SurfaceSnapshot {
  #vertices: GPUBuffer | null = null;
  #indices: GPUBuffer[] = [];
  #drawArgs: GPUBuffer | null = null;
  /** What the copy holds: welded vertices, and indices per shard. */
  #vertexCount = 0;
  #indexCounts: number[] = [];
  /** What the renderer binds: the copies (slotData and blockToSlot are the surface's, read through). */
  readonly drawData: IsosurfaceDrawData;

  constructor(
    private readonly device: GPUDevice,
    source: IsosurfaceDrawData,
  ) {
    // slotData and blockToSlot stay the surface's own (replaced in place on growth: read through)
    this.drawData = Object.defineProperties(
      { vertices: source.vertices, shards: [], info: source.info, version: 0 } as unknown as IsosurfaceDrawData,
      {
        slotData: { get: () => source.slotData, enumerable: true },
        blockToSlot: { get: () => source.blockToSlot, enumerable: true },
      },
    );
  }

  /** Bytes a copy of a surface of `counts` holds, in shards of `perShard` indices. */
  static bytesFor(counts: SurfaceCounts, perShard: number): number {
    const shards = Math.max(1, Math.ceil(counts.indices / perShard));
    return Math.max(1, counts.vertices) * VERTEX_BYTES + Math.max(1, counts.indices) * INDEX_BYTES + shards * DRAW_ARGS_BYTES;
  }

  /** Triangles the copy draws. */
  get triangles(): number {
    return this.#indexCounts.reduce((a, b) => a + b, 0) / 3;
  }

  /** Bytes held now. */
  get byteSize(): number {
    return (this.#vertices?.size ?? 0) + this.#indices.reduce((a, b) => a + b.size, 0) + (this.#drawArgs?.size ?? 0);
  }

  /**
   * Copies the surface `output` holds now (`counts`: its statistics) and
   * draws it from now on. Buffers that are too small are let go before the
   * new ones are made, so the copy never holds two surfaces at once.
   */
  capture(output: SurfaceOutput, source: IsosurfaceDrawData, counts: SurfaceCounts): void {
    const { device } = this;
    const perShard = output.perShard;
    const shards = Math.min(output.shards.length, Math.max(1, Math.ceil(counts.indices / perShard)));
    const vertices = Math.min(counts.vertices, output.weldedCapacity);
    const sizes = Array.from({ length: shards }, (_, k) => Math.max(0, Math.min(perShard, counts.indices - k * perShard)));
    // kept while the copy fits and is not more than twice what it must hold (a smaller surface gives memory back)
    const holds = (b: GPUBuffer, bytes: number) => b.size >= bytes && b.size <= 2 * bytes + 4096;
    const fits =
      this.#vertices !== null &&
      holds(this.#vertices, Math.max(1, vertices) * VERTEX_BYTES) &&
      this.#indices.length === shards &&
      this.#indices.every((b, k) => holds(b, Math.max(1, sizes[k]) * INDEX_BYTES));
    if (!fits) {
      this.#destroyBuffers();
      this.#vertices = device.createBuffer({
        label: 'SurfaceSnapshot.vertices',
        size: Math.max(1, vertices) * VERTEX_BYTES,
        usage: GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC,
      });
      this.#indices = sizes.map((n, k) =>
        device.createBuffer({
          label: `SurfaceSnapshot.indices${k}`,
          size: Math.max(1, n) * INDEX_BYTES,
          usage: GPUBufferUsage.INDEX | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC,
        }),
      );
      this.#drawArgs = device.createBuffer({
        label: 'SurfaceSnapshot.drawArgs',
        size: shards * DRAW_ARGS_BYTES,
        usage: GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC,
      });
    }
    this.#vertexCount = vertices;
    this.#indexCounts = sizes;
    const encoder = device.createCommandEncoder({ label: 'SurfaceSnapshot.capture' });
    // copy sizes are multiples of 4 (12-byte vertices, 4-byte indices, 20-byte records)
    if (vertices > 0) encoder.copyBufferToBuffer(output.vertices, 0, this.#vertices!, 0, vertices * VERTEX_BYTES);
    sizes.forEach((n, k) => {
      if (n > 0) encoder.copyBufferToBuffer(output.shards[k].indices, 0, this.#indices[k], 0, n * INDEX_BYTES);
    });
    encoder.copyBufferToBuffer(output.drawArgs, 0, this.#drawArgs!, 0, shards * DRAW_ARGS_BYTES);
    device.queue.submit([encoder.finish()]);
    Object.assign(this.drawData, {
      vertices: this.#vertices,
      shards: this.#indices.map((indices, k) => ({ indices, drawArgs: this.#drawArgs!, drawArgsOffset: k * DRAW_ARGS_BYTES })),
      info: source.info,
      version: this.drawData.version + 1,
    });
  }

  /**
   * The copy as an indexed mesh (what is drawn, not what the surface has
   * computed since); waits for the GPU. `dims`: the volume's voxels per axis.
   */
  readMesh(dims: readonly [number, number, number]): Promise<SurfaceMesh> {
    const shards = this.#indices.map((indices, k) => ({ indices, count: this.#indexCounts[k] }));
    return readWeldedMesh(this.device, this.#vertices, this.#vertexCount, shards, dims);
  }

  #destroyBuffers(): void {
    this.#vertices?.destroy();
    for (const b of this.#indices) b.destroy();
    this.#drawArgs?.destroy();
    this.#vertices = null;
    this.#indices = [];
    this.#drawArgs = null;
    this.#vertexCount = 0;
    this.#indexCounts = [];
  }

  destroy(): void {
    this.#destroyBuffers();
    this.drawData.shards = [];
  }
}
