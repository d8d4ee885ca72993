// CPU model of the block cache (paper Algorithm 1 as the GPU runs it, see
// lru-cache.ts): the reference the cache tests compare the GPU state with,
// slot for slot. Also the CPU rule for active blocks.
import type { Dims } from '../core/naming.ts';
import { AGE_MAX, DEFAULT_GROUP_EDGE_BLOCKS, NONE } from './layout.ts';

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

export class LruCacheModel {
  slotAge = new Uint32Array(0);
  slotToBlock = new Uint32Array(0);
  readonly blockToSlot: Uint32Array;
  slotsUsed = 0;

  constructor(readonly blockCount: number, capacity: number) {
    this.blockToSlot = new Uint32Array(blockCount);
    this.reset(capacity);
  }

  get capacity(): number {
    return this.slotAge.length;
  }

  /** Everything empty (age NONE, no blocks), `capacity` slots. */
  reset(capacity: number): void {
    this.slotAge = new Uint32Array(capacity).fill(NONE);
    this.slotToBlock = new Uint32Array(capacity).fill(NONE);
    this.blockToSlot.fill(NONE);
    this.slotsUsed = 0;
  }

  /** New slots are empty; every cached block stays in its slot. */
  grow(capacity: number): void {
    const age = new Uint32Array(capacity).fill(NONE);
    const map = new Uint32Array(capacity).fill(NONE);
    age.set(this.slotAge);
    map.set(this.slotToBlock);
    this.slotAge = age;
    this.slotToBlock = map;
  }

  /**
   * One update for the active list (ascending block ids). Returns null when
   * the cache is too small (more active blocks than slots), leaving it unchanged,
   * as the GPU does.
   */
  update(active: readonly number[]): ModelUpdate | null {
    const slots = this.capacity;
    if (active.length > slots) return null;
    // age_slots: age by one, saturating; empty slots keep NONE; all available
    const available = new Uint8Array(slots).fill(1);
    for (let s = 0; s < slots; s++) if (this.slotToBlock[s] !== NONE) this.slotAge[s] = Math.min(this.slotAge[s] + 1, AGE_MAX);
    // mark_cached
    const newBlocks: number[] = [];
    for (const b of active) {
      const s = this.blockToSlot[b];
      if (s !== NONE) {
        this.slotAge[s] = 0;
        available[s] = 0;
      } else {
        newBlocks.push(b);
      }
    }
    const evicted: number[] = [];
    if (newBlocks.length === 0) return { newBlocks, evicted };
    // available slots in slot order, sorted by the low 16 bits of the age,
    // descending, stably (empty slots: 0xffff, first)
    const order: number[] = [];
    for (let s = 0; s < slots; s++) if (available[s]) order.push(s);
    const key = (s: number) => this.slotAge[s] & 0xffff;
    order.sort((a, b) => key(b) - key(a) || a - b);
    this.slotsUsed = Math.min(this.slotsUsed + newBlocks.length, slots);
    newBlocks.forEach((b, i) => {
      const s = order[i];
      const old = this.slotToBlock[s];
      if (old !== NONE) {
        this.blockToSlot[old] = NONE;
        evicted.push(old);
      }
      this.slotToBlock[s] = b;
      this.blockToSlot[b] = s;
      this.slotAge[s] = 0;
    });
    return { newBlocks, evicted };
  }
}
