/** A least-recently-used map bounded in bytes (the CPU-side caches of compressed chunks and of decoded source chunks). */
export class ByteLru<K, V = Uint8Array> {
  #map = new Map<K, V>();
  #bytes = 0;
  constructor(
    readonly capacityBytes: number,
    private readonly sizeOf: (value: V) => number = (v) => (v as unknown as Uint8Array).length,
  ) {}
  get bytes(): number {
    return this.#bytes;
  }
  get size(): number {
    return this.#map.size;
  }
  get(key: K): V | undefined {
    const v = this.#map.get(key);
    if (v !== undefined) {
      this.#map.delete(key);
      this.#map.set(key, v);
    }
    return v;
  }
  has(key: K): boolean {
    return this.#map.has(key);
  }
  set(key: K, value: V): void {
    if (this.sizeOf(value) > this.capacityBytes) return;
    const old = this.#map.get(key);
    if (old !== undefined) {
      this.#bytes -= this.sizeOf(old);
      this.#map.delete(key);
    }
    this.#map.set(key, value);
    this.#bytes += this.sizeOf(value);
    for (const [k, v] of this.#map) {
      if (this.#bytes <= this.capacityBytes) break;
      this.#map.delete(k);
      this.#bytes -= this.sizeOf(v);
    }
  }
  clear(): void {
    this.#map.clear();
    this.#bytes = 0;
  }
}
