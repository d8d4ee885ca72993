/** A least-recently-used map bounded in bytes (the CPU-side cache of compressed chunks). */
export class ByteLru<K> {
  #map = new Map<K, Uint8Array>();
  #bytes = 0;
  constructor(readonly capacityBytes: number) {}
  get bytes(): number {
    return this.#bytes;
  }
  get size(): number {
    return this.#map.size;
  }
  get(key: K): Uint8Array | undefined {
    const v = this.#map.get(key);
    if (v) {
      this.#map.delete(key);
      this.#map.set(key, v);
    }
    return v;
  }
  has(key: K): boolean {
    return this.#map.has(key);
  }
  set(key: K, value: Uint8Array): void {
    if (value.length > this.capacityBytes) return;
    const old = this.#map.get(key);
    if (old) {
      this.#bytes -= old.length;
      this.#map.delete(key);
    }
    this.#map.set(key, value);
    this.#bytes += value.length;
    for (const [k, v] of this.#map) {
      if (this.#bytes <= this.capacityBytes) break;
      this.#map.delete(k);
      this.#bytes -= v.length;
    }
  }
  clear(): void {
    this.#map.clear();
    this.#bytes = 0;
  }
}
