// Small pieces shared by the zfp GPU classes: buffer references, running
// work in the caller's pass or in one of our own, bind-group and uniform
// caches (so recording the same work again allocates nothing).

/** A whole buffer, or a range of one (offset a multiple of minStorageBufferOffsetAlignment). */
export type GpuBufferRef = GPUBuffer | { buffer: GPUBuffer; offset?: number; size?: number };

/** A u32 written by an earlier GPU pass: `buffer` (STORAGE usage) at byte `offset` (multiple of 4). */
export interface GpuCount {
  buffer: GPUBuffer;
  offset: number;
}

/** Where work is recorded: the caller's command encoder (we open a pass) or compute pass. */
export type ComputeTarget = GPUCommandEncoder | GPUComputePassEncoder;

export function binding(ref: GpuBufferRef): GPUBufferBinding {
  if ('mapState' in ref) return { buffer: ref };
  const b: GPUBufferBinding = { buffer: ref.buffer, offset: ref.offset ?? 0 };
  if (ref.size !== undefined) b.size = ref.size;
  return b;
}

export function refBuffer(ref: GpuBufferRef): GPUBuffer {
  return 'mapState' in ref ? ref : ref.buffer;
}

/** Bytes visible through the reference. */
export function refSize(ref: GpuBufferRef): number {
  if ('mapState' in ref) return ref.size;
  return ref.size ?? ref.buffer.size - (ref.offset ?? 0);
}

function isCommandEncoder(t: ComputeTarget): t is GPUCommandEncoder {
  return typeof (t as GPUCommandEncoder).beginComputePass === 'function';
}

/** Runs `record` in `target` if it is a pass, else in a new pass of the command encoder. */
export function inPass(target: ComputeTarget, label: string, record: (pass: GPUComputePassEncoder) => void, timestampWrites?: GPUComputePassTimestampWrites): void {
  if (!isCommandEncoder(target)) {
    record(target);
    return;
  }
  const desc: GPUComputePassDescriptor = { label };
  if (timestampWrites) desc.timestampWrites = timestampWrites;
  const pass = target.beginComputePass(desc);
  record(pass);
  pass.end();
}

const ids = new WeakMap<object, number>();
let nextId = 1;
/** A stable number per object, for cache keys. */
export function objectId(o: object): number {
  let id = ids.get(o);
  if (id === undefined) {
    id = nextId++;
    ids.set(o, id);
  }
  return id;
}

export function refKey(ref: GpuBufferRef): string {
  const b = binding(ref);
  return `${objectId(b.buffer)}@${b.offset ?? 0}+${b.size ?? '*'}`;
}

/** Bind groups by key; cleared when it grows past `limit` (bind groups are cheap to rebuild). */
export class BindGroupCache {
  private readonly map = new Map<string, GPUBindGroup>();
  constructor(private readonly limit = 512) {}
  get(key: string, create: () => GPUBindGroup): GPUBindGroup {
    let g = this.map.get(key);
    if (!g) {
      if (this.map.size >= this.limit) this.map.clear();
      g = create();
      this.map.set(key, g);
    }
    return g;
  }
  clear(): void {
    this.map.clear();
  }
}

/**
 * Small uniform records (<= 256 bytes) allocated once per distinct content key
 * from pages of 256-byte slots, kept until destroy(): recording the same work
 * again reuses them, and nothing a pending command buffer uses is freed early.
 */
export class UniformSlots {
  private static readonly SLOT = 256;
  private static readonly PER_PAGE = 64;
  private readonly pages: GPUBuffer[] = [];
  private used = 0;
  private readonly byKey = new Map<string, GPUBufferBinding>();

  constructor(private readonly device: GPUDevice, private readonly label: string) {}

  get(key: string, data: Uint32Array<ArrayBuffer>): GPUBufferBinding {
    let b = this.byKey.get(key);
    if (b) return b;
    const page = Math.floor(this.used / UniformSlots.PER_PAGE);
    if (page === this.pages.length) {
      this.pages.push(this.device.createBuffer({ label: `${this.label}.uniforms${page}`, size: UniformSlots.SLOT * UniformSlots.PER_PAGE, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST }));
    }
    const offset = (this.used % UniformSlots.PER_PAGE) * UniformSlots.SLOT;
    this.used++;
    this.device.queue.writeBuffer(this.pages[page], offset, data);
    b = { buffer: this.pages[page], offset, size: Math.max(16, data.byteLength) };
    this.byKey.set(key, b);
    return b;
  }

  destroy(): void {
    for (const p of this.pages) p.destroy();
    this.pages.length = 0;
    this.byKey.clear();
    this.used = 0;
  }
}
