// Caches keyed by tuples of objects (buffers, streams, layouts) and numbers
// (offsets, sizes, parameters), walked one key at a time:
//
//   const group = cache.ref(a.blockIds).ref(a.slotIds).key(shard).get(() => device.createBindGroup(...));
//
// Objects index WeakMaps (entries go away with the buffers), numbers index
// Maps; nothing is allocated and no string is built once a tuple has been
// seen, so recording the same work again costs a few map lookups.

/** An element of a cache key. */
export type CacheKey = object | number;

/** A buffer, or a range of one (the shape of GpuBufferRef and GPUBufferBinding). */
type BufferRange = GPUBuffer | { buffer: GPUBuffer; offset?: number; size?: number };

export class CacheNode<V> {
  private objects?: WeakMap<object, CacheNode<V>>;
  private numbers?: Map<number, CacheNode<V>>;
  private value?: V;

  constructor(private readonly owner: KeyedCache<V>) {}

  /** The node one key further down. */
  key(k: CacheKey): CacheNode<V> {
    let next: CacheNode<V> | undefined;
    if (typeof k === 'number') {
      this.numbers ??= new Map();
      next = this.numbers.get(k);
      if (!next) this.numbers.set(k, (next = new CacheNode(this.owner)));
    } else {
      this.objects ??= new WeakMap();
      next = this.objects.get(k);
      if (!next) this.objects.set(k, (next = new CacheNode(this.owner)));
    }
    return next;
  }

  /** Three keys for a buffer range: the buffer, its offset and its size (-1: to the end). */
  ref(r: BufferRange): CacheNode<V> {
    if ('mapState' in r) return this.key(r).key(0).key(-1);
    return this.key(r.buffer)
      .key(r.offset ?? 0)
      .key(r.size ?? -1);
  }

  /** The value at this key, made by `make` the first time. */
  get(make: () => V): V {
    if (this.value === undefined) {
      this.value = make();
      this.owner.added();
    }
    return this.value;
  }
}

/**
 * A cache of values by key tuples. `limit` bounds the values held: past it the
 * cache starts empty again (values are cheap to make again; number keys, unlike
 * buffers, never go away by themselves).
 */
export class KeyedCache<V> {
  private root = new CacheNode<V>(this);
  private count = 0;

  constructor(private readonly limit = 4096) {}

  /** The node of the first key. */
  key(k: CacheKey): CacheNode<V> {
    return this.root.key(k);
  }

  /** The node of a buffer range (buffer, offset, size). */
  ref(r: BufferRange): CacheNode<V> {
    return this.root.ref(r);
  }

  /** The value for the tuple `keys` (for short tuples known as an array). */
  get(keys: readonly CacheKey[], make: () => V): V {
    let node = this.root;
    for (const k of keys) node = node.key(k);
    return node.get(make);
  }

  /** @internal a value was made. */
  added(): void {
    if (++this.count > this.limit) this.clear();
  }

  /** Forgets everything (e.g. after the owner's own buffers were replaced). */
  clear(): void {
    this.root = new CacheNode<V>(this);
    this.count = 0;
  }
}

/** The one bind-group cache of the project: bind groups by the buffers (and ranges, numbers) they bind. */
export class BindGroupCache extends KeyedCache<GPUBindGroup> {}
