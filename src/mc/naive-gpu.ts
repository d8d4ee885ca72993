// Naive data-parallel marching cubes in WebGPU over a whole decompressed
// volume: the baseline of the paper's section 3.3.3 (Table 2), which the
// block-compressed pipeline (src/isosurface/) improves on. Like the paper's
// (and the classic CUDA sample): a kernel over every cell marks the active
// ones, a prefix sum and a stream compaction list their IDs, a kernel over the
// active cells writes each one's vertex count, a second prefix sum gives each
// cell its output offset and the total, and a last kernel over the active
// cells writes the triangle soup. The passes after the first are dispatched
// indirectly from the GPU's own counts; nothing is read back between them.
//
// Same case table, corner and edge numbering and interpolation formula as the
// serial MC (src/mc/README.md), so the soups are the same triangles (vertices
// within WGSL's division rounding). The whole float32 volume must sit in GPU
// memory, plus three u32 per cell (mask, offsets, active IDs): that memory is
// exactly what the block-compressed pipeline avoids.
//
//   const mc = await NaiveMarchingCubes.create(device, { dims });
//   const r = await mc.extract(volumeBuffer, iso);     // counts, GPU ms; grows the soup if needed
//   const soup = await mc.readPositions(r.vertices);   // xyz per vertex, 3 vertices per triangle
import naiveMcWgsl from '../../shaders/mc/naive_mc.wgsl?raw';
import { KeyedCache } from '../gpu/bind-group-cache.ts';
import { dispatchWorkgroups, gridSnippet } from '../gpu/dispatch.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { ExclusiveScan, IndirectArgs, StreamCompactIds } from '../primitives/index.ts';
import { createCaseTableBuffer, mcCaseTableSnippet } from './case-table-wgsl.ts';
import type { Dims3 } from './serial-mc.ts';

export interface NaiveMcOptions {
  /** Grid points per axis of the volumes this instance contours (x fastest). */
  dims: Dims3;
  /** Vertices the soup buffer holds at first (grown on demand). Default: 2^16. */
  initialVertexCapacity?: number;
  /** Tests lower it to exercise 2D grids. Default: the device's limit. */
  maxWorkgroupsPerDimension?: number;
  /** Per-stage GPU times from timestamp queries when the device has them. Default true. */
  timing?: boolean;
}

export interface NaiveMcResult {
  iso: number;
  activeCells: number;
  vertices: number;
  triangles: number;
  /** GPU time from the first to the last pass (timestamps), else submit-to-readback wall time. */
  gpuMs: number;
  /** Per stage (timestamps only). */
  stages: { label: string; ms: number }[];
  /** Wall time from submit to the counts being read, ms (includes a re-emit after growth). */
  wallMs: number;
  /** The soup did not fit; the buffer grew and the emit pass ran again. */
  grew: boolean;
  timing: 'timestamp-query' | 'queue-wall-time';
}

const STAGES = ['mark active cells', 'scan + compact', 'count vertices', 'scan counts', 'emit vertices'] as const;
const MARKERS = STAGES.length + 1;
const WG = 64;
const COUNTER_BYTES = 16;
const PARAMS_BYTES = 48;

export class NaiveMarchingCubes {
  readonly dims: Dims3;
  readonly cellCount: number;
  private vertexCapacity: number;
  private positionsBuffer: GPUBuffer;
  private emitGroup!: GPUBindGroup;
  private readonly volumeGroups = new KeyedCache<VolumeGroups>();
  private readonly querySet?: GPUQuerySet;
  private readonly resolveBuffer?: GPUBuffer;
  private readonly staging: GPUBuffer;
  private readonly paramsData = new ArrayBuffer(PARAMS_BYTES);

  private constructor(
    private readonly device: GPUDevice,
    options: NaiveMcOptions,
    private readonly pipelines: { mark: GPUComputePipeline; count: GPUComputePipeline; emit: GPUComputePipeline },
    private readonly scan: ExclusiveScan,
    private readonly compact: StreamCompactIds,
    private readonly indirect: IndirectArgs,
    private readonly maxPerDim: number,
    readonly timingSource: 'timestamp-query' | 'queue-wall-time',
    /** Per cell: the 0/1 mask, then (reused) the active cells' vertex counts. */
    private readonly mask: GPUBuffer,
    /** Per cell: the mask's scan, then (reused) the vertex offsets. */
    private readonly offsets: GPUBuffer,
    private readonly activeIds: GPUBuffer,
    private readonly counters: GPUBuffer,
    private readonly params: GPUBuffer,
    private readonly table: GPUBuffer,
  ) {
    this.dims = options.dims;
    this.cellCount = cellsOf(options.dims);
    this.vertexCapacity = Math.max(3, options.initialVertexCapacity ?? 1 << 16);
    this.positionsBuffer = this.createPositions(this.vertexCapacity);
    if (timingSource === 'timestamp-query') {
      this.querySet = device.createQuerySet({ label: 'NaiveMc.stageTimes', type: 'timestamp', count: MARKERS });
      this.resolveBuffer = device.createBuffer({
        label: 'NaiveMc.stageTimes.resolve',
        size: MARKERS * 8,
        usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC,
      });
    }
    this.staging = device.createBuffer({
      label: 'NaiveMc.staging',
      size: COUNTER_BYTES + MARKERS * 8,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    this.bindEmit();
  }

  static async create(device: GPUDevice, options: NaiveMcOptions): Promise<NaiveMarchingCubes> {
    const [nx, ny, nz] = options.dims;
    for (const n of options.dims) if (!Number.isInteger(n) || n < 1) throw new RangeError(`bad volume dims ${options.dims.join('x')}`);
    const cells = cellsOf(options.dims);
    const limits = device.limits;
    const binding = Math.min(limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    const volumeBytes = nx * ny * nz * 4;
    if (volumeBytes > binding || cells * 4 > binding || nx * ny * nz > 2 ** 32 - 1) {
      throw new RangeError(
        `naive marching cubes needs the whole ${options.dims.join('x')} float32 volume (${mb(volumeBytes)}) and 4 bytes per cell in single storage bindings; ` +
          `this device allows ${mb(binding)} per binding`,
      );
    }
    const maxPerDim = options.maxWorkgroupsPerDimension ?? limits.maxComputeWorkgroupsPerDimension;
    const parts = [gridSnippet, mcCaseTableSnippet, { name: 'shaders/mc/naive_mc.wgsl', code: naiveMcWgsl }];
    const constants = { WG, MAX_WG_PER_DIM: maxPerDim };
    const [mark, count, emit, scan, compact, indirect] = await Promise.all([
      createComputePipeline(device, 'NaiveMc.markActive', parts, 'mark_active', { constants }),
      createComputePipeline(device, 'NaiveMc.countVertices', parts, 'count_vertices', { constants }),
      createComputePipeline(device, 'NaiveMc.emitVertices', parts, 'emit_vertices', { constants }),
      ExclusiveScan.create(device, { capacity: Math.max(1, cells), maxWorkgroupsPerDimension: maxPerDim }),
      StreamCompactIds.create(device, { maxWorkgroupsPerDimension: maxPerDim }),
      IndirectArgs.create(device, { itemsPerWorkgroup: WG, label: 'NaiveMc.activeArgs', maxWorkgroupsPerDimension: maxPerDim }),
    ]);
    const perCell = (label: string) =>
      device.createBuffer({
        label: `NaiveMc.${label}`,
        size: Math.max(4, cells * 4),
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
      });
    const timing = options.timing !== false && device.features.has('timestamp-query') ? 'timestamp-query' : 'queue-wall-time';
    return new NaiveMarchingCubes(
      device,
      options,
      { mark, count, emit },
      scan,
      compact,
      indirect,
      maxPerDim,
      timing,
      perCell('mask'),
      perCell('offsets'),
      perCell('activeIds'),
      device.createBuffer({
        label: 'NaiveMc.counters',
        size: COUNTER_BYTES,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
      }),
      device.createBuffer({ label: 'NaiveMc.params', size: PARAMS_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST }),
      createCaseTableBuffer(device),
    );
  }

  /** The soup: 3 f32 per vertex (voxel index space), 3 vertices per triangle. Replaced when it grows. */
  get positions(): GPUBuffer {
    return this.positionsBuffer;
  }

  get capacity(): number {
    return this.vertexCapacity;
  }

  /** Bytes of GPU memory this instance holds (the volume, the caller's, not included). */
  get memoryBytes(): number {
    return 3 * Math.max(4, this.cellCount * 4) + this.vertexCapacity * 12 + COUNTER_BYTES + PARAMS_BYTES + 2048;
  }

  /** Grows the soup buffer to hold `vertices` (never shrinks). */
  reserve(vertices: number): void {
    if (vertices <= this.vertexCapacity) return;
    const binding = Math.min(this.device.limits.maxStorageBufferBindingSize, this.device.limits.maxBufferSize);
    if (vertices * 12 > binding) {
      throw new RangeError(
        `the surface has ${vertices} vertices (${mb(vertices * 12)}), more than one storage binding holds (${mb(binding)})`,
      );
    }
    this.positionsBuffer.destroy();
    this.vertexCapacity = vertices;
    this.positionsBuffer = this.createPositions(vertices);
    this.bindEmit();
  }

  /**
   * Records the whole computation for `iso` on `volume` (f32, x fastest, dims
   * as created; STORAGE usage). Writes the isovalue with queue.writeBuffer, so
   * record one surface per submission.
   */
  encode(encoder: GPUCommandEncoder, volume: GPUBuffer, iso: number): void {
    this.writeParams(iso);
    const groups = this.groupsFor(volume);
    const cells = this.cellCount;
    const count = { buffer: this.counters, offset: 0 };
    encoder.clearBuffer(this.counters);
    this.marker(encoder, 0);
    {
      const pass = encoder.beginComputePass({ label: 'NaiveMc.markActive' });
      pass.setPipeline(this.pipelines.mark);
      pass.setBindGroup(0, groups.mark);
      pass.setBindGroup(1, groups.markOut);
      dispatchWorkgroups(pass, Math.ceil(cells / WG), this.maxPerDim);
      pass.end();
    }
    this.marker(encoder, 1);
    this.scan.encode(encoder, { input: this.mask, output: this.offsets, count: cells, totalOut: count });
    this.compact.encode(encoder, { mask: this.mask, offsets: this.offsets, output: this.activeIds, count: cells });
    this.marker(encoder, 2);
    this.indirect.encode(encoder, { count });
    {
      const pass = encoder.beginComputePass({ label: 'NaiveMc.countVertices' });
      pass.setPipeline(this.pipelines.count);
      pass.setBindGroup(0, groups.count);
      pass.setBindGroup(1, this.countGroup());
      pass.dispatchWorkgroupsIndirect(this.indirect.buffer, 0);
      pass.end();
    }
    this.marker(encoder, 3);
    this.scan.encode(encoder, { input: this.mask, output: this.offsets, count, totalOut: { buffer: this.counters, offset: 4 } });
    this.marker(encoder, 4);
    this.encodeEmit(encoder, groups.emit);
    this.marker(encoder, 5);
  }

  /** Computes the surface at `iso` and waits for its counts (and times). */
  async extract(volume: GPUBuffer, iso: number): Promise<NaiveMcResult> {
    const encoder = this.device.createCommandEncoder({ label: 'NaiveMc.extract' });
    this.encode(encoder, volume, iso);
    this.encodeReadback(encoder);
    const start = performance.now();
    this.device.queue.submit([encoder.finish()]);
    let read = await this.readStaging();
    let grew = false;
    const vertices = read.counters[1];
    if (vertices > this.vertexCapacity) {
      // Only the emit pass runs again: the active list and offsets are still in their buffers.
      grew = true;
      this.reserve(Math.max(vertices, Math.ceil(this.vertexCapacity * 1.5)));
      this.device.queue.writeBuffer(this.params, 32, new Uint32Array([this.vertexCapacity]));
      const again = this.device.createCommandEncoder({ label: 'NaiveMc.reEmit' });
      this.marker(again, 4);
      this.encodeEmit(again, this.groupsFor(volume).emit);
      this.marker(again, 5);
      this.encodeReadback(again);
      this.device.queue.submit([again.finish()]);
      const second = await this.readStaging();
      // Stage times: the first attempt's, with the emit pass of the second.
      read = {
        counters: second.counters,
        ticks:
          read.ticks && second.ticks
            ? [...read.ticks.slice(0, 4), read.ticks[4], read.ticks[4] + (second.ticks[5] - second.ticks[4])]
            : undefined,
      };
    }
    const wallMs = performance.now() - start;
    const stages = read.ticks
      ? STAGES.map((label, k) => ({ label, ms: Math.max(0, Number(read.ticks![k + 1] - read.ticks![k])) / 1e6 }))
      : [];
    const gpuMs = read.ticks ? stages.reduce((s, x) => s + x.ms, 0) : wallMs;
    return {
      iso: Math.fround(iso),
      activeCells: read.counters[0],
      vertices,
      triangles: vertices / 3,
      gpuMs,
      stages,
      wallMs,
      grew,
      timing: this.timingSource,
    };
  }

  /** The first `vertices` vertices of the soup (after extract). */
  async readPositions(vertices: number): Promise<Float32Array> {
    const n = Math.min(vertices, this.vertexCapacity) * 3;
    if (n === 0) return new Float32Array(0);
    const staging = this.device.createBuffer({
      label: 'NaiveMc.readPositions',
      size: n * 4,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    try {
      const encoder = this.device.createCommandEncoder({ label: 'NaiveMc.readPositions' });
      encoder.copyBufferToBuffer(this.positionsBuffer, 0, staging, 0, n * 4);
      this.device.queue.submit([encoder.finish()]);
      await staging.mapAsync(GPUMapMode.READ);
      return new Float32Array(staging.getMappedRange().slice(0));
    } finally {
      staging.destroy();
    }
  }

  destroy(): void {
    for (const b of [
      this.mask,
      this.offsets,
      this.activeIds,
      this.counters,
      this.params,
      this.table,
      this.positionsBuffer,
      this.staging,
      this.resolveBuffer,
    ])
      b?.destroy();
    this.querySet?.destroy();
    this.scan.destroy();
    this.compact.destroy();
    this.indirect.destroy();
  }

  // ---------------------------------------------------------------- internals

  private createPositions(vertices: number): GPUBuffer {
    return this.device.createBuffer({
      label: 'NaiveMc.positions',
      size: Math.max(16, vertices * 12),
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.VERTEX,
    });
  }

  private writeParams(iso: number): void {
    const [nx, ny, nz] = this.dims;
    const u = new Uint32Array(this.paramsData);
    const f = new Float32Array(this.paramsData);
    u.set([nx, ny, nz], 0);
    f[3] = iso;
    u.set([Math.max(0, nx - 1), Math.max(0, ny - 1), Math.max(0, nz - 1), this.cellCount, this.vertexCapacity], 4);
    this.device.queue.writeBuffer(this.params, 0, this.paramsData);
  }

  private marker(encoder: GPUCommandEncoder, index: number): void {
    if (!this.querySet) return;
    encoder
      .beginComputePass({ label: `NaiveMc.marker${index}`, timestampWrites: { querySet: this.querySet, beginningOfPassWriteIndex: index } })
      .end();
  }

  private encodeReadback(encoder: GPUCommandEncoder): void {
    encoder.copyBufferToBuffer(this.counters, 0, this.staging, 0, COUNTER_BYTES);
    if (this.querySet && this.resolveBuffer) {
      encoder.resolveQuerySet(this.querySet, 0, MARKERS, this.resolveBuffer, 0);
      encoder.copyBufferToBuffer(this.resolveBuffer, 0, this.staging, COUNTER_BYTES, MARKERS * 8);
    }
  }

  private async readStaging(): Promise<{ counters: Uint32Array; ticks?: bigint[] }> {
    await this.staging.mapAsync(GPUMapMode.READ);
    try {
      const bytes = this.staging.getMappedRange().slice(0);
      const counters = new Uint32Array(bytes, 0, COUNTER_BYTES / 4);
      const ticks = this.querySet ? Array.from(new BigInt64Array(bytes, COUNTER_BYTES, MARKERS)) : undefined;
      return { counters, ticks };
    } finally {
      this.staging.unmap();
    }
  }

  private encodeEmit(encoder: GPUCommandEncoder, volumeGroup: GPUBindGroup): void {
    const pass = encoder.beginComputePass({ label: 'NaiveMc.emitVertices' });
    pass.setPipeline(this.pipelines.emit);
    pass.setBindGroup(0, volumeGroup);
    pass.setBindGroup(1, this.emitGroup);
    pass.dispatchWorkgroupsIndirect(this.indirect.buffer, 0);
    pass.end();
  }

  private countBindGroup?: GPUBindGroup;
  private countGroup(): GPUBindGroup {
    this.countBindGroup ??= this.device.createBindGroup({
      label: 'NaiveMc.countGroup',
      layout: this.pipelines.count.getBindGroupLayout(1),
      entries: [
        { binding: 0, resource: { buffer: this.counters } },
        { binding: 1, resource: { buffer: this.activeIds } },
        { binding: 2, resource: { buffer: this.mask } },
      ],
    });
    return this.countBindGroup;
  }

  private bindEmit(): void {
    this.emitGroup = this.device.createBindGroup({
      label: 'NaiveMc.emitGroup',
      layout: this.pipelines.emit.getBindGroupLayout(1),
      entries: [
        { binding: 0, resource: { buffer: this.counters } },
        { binding: 1, resource: { buffer: this.activeIds } },
        { binding: 3, resource: { buffer: this.offsets } },
        { binding: 4, resource: { buffer: this.positionsBuffer } },
      ],
    });
  }

  /** The bind groups that hold `volume` (group 0 of each pipeline) and mark's output group. */
  private groupsFor(volume: GPUBuffer): VolumeGroups {
    const [nx, ny, nz] = this.dims;
    const bytes = nx * ny * nz * 4;
    if (volume.size < bytes) throw new RangeError(`volume buffer has ${volume.size} bytes, ${this.dims.join('x')} float32 needs ${bytes}`);
    return this.volumeGroups.key(volume).get(() => {
      const group0 = (p: GPUComputePipeline, label: string) =>
        this.device.createBindGroup({
          label: `NaiveMc.${label}.volume`,
          layout: p.getBindGroupLayout(0),
          entries: [
            { binding: 0, resource: { buffer: this.params } },
            { binding: 1, resource: { buffer: volume, size: bytes } },
            { binding: 2, resource: { buffer: this.table } },
          ],
        });
      return {
        mark: group0(this.pipelines.mark, 'mark'),
        markOut: this.device.createBindGroup({
          label: 'NaiveMc.markGroup',
          layout: this.pipelines.mark.getBindGroupLayout(1),
          entries: [{ binding: 0, resource: { buffer: this.mask } }],
        }),
        count: group0(this.pipelines.count, 'count'),
        emit: group0(this.pipelines.emit, 'emit'),
      };
    });
  }
}

interface VolumeGroups {
  mark: GPUBindGroup;
  markOut: GPUBindGroup;
  count: GPUBindGroup;
  emit: GPUBindGroup;
}

function cellsOf(dims: Dims3): number {
  const [nx, ny, nz] = dims;
  return nx < 2 || ny < 2 || nz < 2 ? 0 : (nx - 1) * (ny - 1) * (nz - 1);
}

function mb(bytes: number): string {
  return `${(bytes / 2 ** 20).toFixed(1)} MiB`;
}
