// CPU model of the block cache (paper Algorithm 1 as the GPU runs it, see
// lru-cache.ts): the reference the cache tests compare the GPU state with,
// slot for slot. Also the CPU rule for active blocks.
import type { Dims } from '../core/naming.ts';
import { DEFAULT_GROUP_EDGE_BLOCKS, NONE } from './layout.ts';

/**
 * Active blocks for `iso`: lo < iso <= hi over the 27-block neighbourhood of
 * each block, in the GPU's order (active-blocks.ts): group-major over groups
 * of `groupEdge`^3 blocks in raster order, raster order within each group.
 */
export function activeBlocks(ranges: Float32Array, grid: Dims, iso: number, groupEdge = DEFAULT_GROUP_EDGE_BLOCKS): number[] {
  const [gx, gy, gz] = grid;
  const t = Math.fround(iso);
  const out: { b: number; key: number }[] = [];
  const groups = [Math.ceil(gx / groupEdge), Math.ceil(gy / groupEdge), Math.ceil(gz / groupEdge)];
  for (let z = 0; z < gz; z++) {
    for (let y = 0; y < gy; y++) {
      for (let x = 0; x < gx; x++) {
        let lo = Infinity;
        let hi = -Infinity;
        for (let k = Math.max(0, z - 1); k <= Math.min(gz - 1, z + 1); k++) {
          for (let j = Math.max(0, y - 1); j <= Math.min(gy - 1, y + 1); j++) {
            for (let i = Math.max(0, x - 1); i <= Math.min(gx - 1, x + 1); i++) {
              const b = i + gx * (j + gy * k);
              lo = Math.min(lo, ranges[2 * b]);
              hi = Math.max(hi, ranges[2 * b + 1]);
            }
          }
        }
        if (lo < t && t <= hi) {
          const e = groupEdge;
          const group = Math.floor(x / e) + groups[0] * (Math.floor(y / e) + groups[1] * Math.floor(z / e));
          const local = (x % e) + e * ((y % e) + e * (z % e));
          out.push({ b: x + gx * (y + gy * z), key: group * e ** 3 + local });
        }
      }
    }
  }
  return out.sort((a, b) => a.key - b.key).map((a) => a.b);
}

export interface ModelUpdate {
  /** Blocks decoded, in the order of the active list. */
  newBlocks: number[];
  /** Blocks evicted to make room. */
  evicted: number[];
}

/**
 * The cache as the GPU keeps it (lru.wgsl): an LRU order of all slots, least
 * recently used first (empty slots first, in slot order, from a reset; after
 * growth the new slots first). Per update: the active blocks already cached
 * are hits; the i-th new block (in active-list order) takes the i-th slot of
 * the order that is not a hit, evicting its block; then every active slot
 * moves to the end, in active-list order.
 */
export class LruCacheModel {
  order: number[] = [];
  slotToBlock = new Uint32Array(0);
  readonly blockToSlot: Uint32Array;
  slotsUsed = 0;

  constructor(
    readonly blockCount: number,
    capacity: number,
  ) {
    this.blockToSlot = new Uint32Array(blockCount);
    this.reset(capacity);
  }

  get capacity(): number {
    return this.slotToBlock.length;
  }

  /** Everything empty, `capacity` slots in slot order. */
  reset(capacity: number): void {
    this.order = Array.from({ length: capacity }, (_, s) => s);
    this.slotToBlock = new Uint32Array(capacity).fill(NONE);
    this.blockToSlot.fill(NONE);
    this.slotsUsed = 0;
  }

  /** New slots are empty and come first in the order; every cached block stays in its slot. */
  grow(capacity: number): void {
    const old = this.capacity;
    const map = new Uint32Array(capacity).fill(NONE);
    map.set(this.slotToBlock);
    this.slotToBlock = map;
    this.order = [...Array.from({ length: capacity - old }, (_, i) => old + i), ...this.order];
  }

  /**
   * One update for the active list (in the GPU's order). Returns null when
   * the cache is too small (more active blocks than slots), leaving it
   * unchanged, as the GPU does.
   */
  update(active: readonly number[]): ModelUpdate | null {
    const slots = this.capacity;
    if (active.length > slots) return null;
    const hits = new Set<number>();
    const newBlocks: number[] = [];
    for (const b of active) {
      const s = this.blockToSlot[b];
      if (s !== NONE) hits.add(s);
      else newBlocks.push(b);
    }
    const evicted: number[] = [];
    const untouched = this.order.filter((s) => !hits.has(s));
    newBlocks.forEach((b, i) => {
      const s = untouched[i];
      const old = this.slotToBlock[s];
      if (old !== NONE) {
        this.blockToSlot[old] = NONE;
        evicted.push(old);
      }
      this.slotToBlock[s] = b;
      this.blockToSlot[b] = s;
    });
    this.slotsUsed = Math.min(this.slotsUsed + newBlocks.length, slots);
    this.order = [...untouched.slice(newBlocks.length), ...active.map((b) => this.blockToSlot[b])];
    return { newBlocks, evicted };
  }
}
