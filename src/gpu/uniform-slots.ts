// Small uniform records (<= 256 bytes), one per distinct content, allocated
// from pages of 256-byte slots and kept until destroy(): recording the same
// work again reuses them (looked up by their words, no string keys), and
// nothing a pending command buffer uses is freed early.
import { KeyedCache } from './bind-group-cache.ts';

const SLOT = 256;
const PER_PAGE = 64;

export class UniformSlots {
  private readonly pages: GPUBuffer[] = [];
  private used = 0;
  private byContent = new KeyedCache<GPUBufferBinding>(Infinity);

  constructor(
    private readonly device: GPUDevice,
    private readonly label: string,
  ) {}

  /** A binding of a slot holding `data` (written once, when first seen). */
  get(data: Uint32Array<ArrayBuffer>): GPUBufferBinding {
    if (data.byteLength > SLOT) throw new RangeError(`UniformSlots: ${data.byteLength} bytes do not fit a ${SLOT}-byte slot`);
    let node = this.byContent.key(data.length);
    for (let i = 0; i < data.length; i++) node = node.key(data[i]);
    return node.get(() => this.allocate(data));
  }

  private allocate(data: Uint32Array<ArrayBuffer>): GPUBufferBinding {
    const page = Math.floor(this.used / PER_PAGE);
    if (page === this.pages.length) {
      this.pages.push(
        this.device.createBuffer({
          label: `${this.label}.uniforms${page}`,
          size: SLOT * PER_PAGE,
          usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
        }),
      );
    }
    const offset = (this.used % PER_PAGE) * SLOT;
    this.used++;
    this.device.queue.writeBuffer(this.pages[page], offset, data);
    return { buffer: this.pages[page], offset, size: Math.max(16, data.byteLength) };
  }

  destroy(): void {
    for (const p of this.pages) p.destroy();
    this.pages.length = 0;
    this.byContent = new KeyedCache<GPUBufferBinding>(Infinity);
    this.used = 0;
  }
}
