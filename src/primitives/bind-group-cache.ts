// Bind groups keyed by the tuple of buffers they bind, so a primitive makes
// each one once per combination of caller buffers. Nested WeakMaps: entries
// go away with the buffers.

interface Node {
  next: WeakMap<object, Node>;
  value?: GPUBindGroup;
}

export class BindGroupCache {
  private root: Node = { next: new WeakMap() };

  get(keys: readonly object[], make: () => GPUBindGroup): GPUBindGroup {
    let node = this.root;
    for (const k of keys) {
      let child = node.next.get(k);
      if (!child) {
        child = { next: new WeakMap() };
        node.next.set(k, child);
      }
      node = child;
    }
    node.value ??= make();
    return node.value;
  }

  /** Forgets everything (after the primitive's own buffers were replaced). */
  clear(): void {
    this.root = { next: new WeakMap() };
  }
}
