// Stable LSD radix sort by u32 key with u32 values, 4 bits per pass, GPU
// path (src/primitives/README.md). One workgroup of WG invocations owns a
// tile of TILE = WG * ITEMS consecutive elements, visited in ITEMS rounds:
// in round k invocation `lid` holds element tile_base + k * WG + lid, so
// consecutive invocations load consecutive keys and values (coalesced), and
// the rounds visit the tile in index order.
//
// `histogram` counts the tile's 16 digits with workgroup atomics into
// table[d * tiles + tile] (digit-major); an exclusive scan of the table
// (ExclusiveScan) gives each (digit, tile) its first output slot; `scatter`
// ranks each element within the tile by its digit, stably: per round every
// invocation sets its bit in its digit's bitmap of WG bits (workgroup
// memory); an element's rank is the number of bits set below its own in its
// digit's bitmap (countOneBits), plus the elements of that digit in earlier
// rounds. Equal digits so keep their order within a tile, tiles are in
// index order in the table: the sort is stable. Descending complements the
// digit (d ^ mask). WG, ITEMS and TILE are consts prepended by the host
// (tileConstants); n and the number of tiles come from a dispatch record
// (one unit = one tile = one workgroup). Barriers are only reached in
// uniform control flow (the early return depends on the workgroup index and
// a uniform). Workgroup variables start zeroed (WGSL).
// Composed after radix_sort_common.wgsl (uniforms, bindings, digit()).

const RADIX: u32 = 16u;
/** Words of one digit's bitmap: one bit per invocation. */
const MASK_WORDS: u32 = (WG + 31u) / 32u;

var<workgroup> digit_counts: array<atomic<u32>, RADIX>;

@compute @workgroup_size(WG)
fn histogram(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= sort.units) {
    return;
  }
  let base = t * TILE;
  for (var k = 0u; k < ITEMS; k++) {
    let i = base + k * WG + lid;
    if (i < sort.n) {
      atomicAdd(&digit_counts[digit(keys_in[i])], 1u);
    }
  }
  workgroupBarrier();
  for (var d = lid; d < RADIX; d += WG) {
    histograms[d * sort.units + t] = atomicLoad(&digit_counts[d]);
  }
}

// Two rounds in flight (ping-pong on k & 1), so a round needs two barriers:
// bitmaps [round][digit][word] and each digit's next output slot [round][digit].
var<workgroup> lane_bits: array<atomic<u32>, 2u * RADIX * MASK_WORDS>;
var<workgroup> next_slot: array<u32, 2u * RADIX>;

fn bits_set(row: u32, words: u32) -> u32 {
  var c = 0u;
  for (var w = 0u; w < words; w++) {
    c += countOneBits(atomicLoad(&lane_bits[row + w]));
  }
  return c;
}

@compute @workgroup_size(WG)
fn scatter(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
           @builtin(local_invocation_index) lid: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= sort.units) {
    return;
  }
  for (var d = lid; d < RADIX; d += WG) {
    next_slot[d] = offsets[d * sort.units + t];
  }
  let word = lid / 32u;
  let bit = 1u << (lid % 32u);
  let base = t * TILE;
  workgroupBarrier();
  for (var k = 0u; k < ITEMS; k++) {
    let cur = k & 1u;
    let i = base + k * WG + lid;
    let valid = i < sort.n;
    var key = 0u;
    var d = 0u;
    if (valid) {
      key = keys_in[i];
      d = digit(key);
      atomicOr(&lane_bits[(cur * RADIX + d) * MASK_WORDS + word], bit);
    }
    workgroupBarrier();
    if (valid) {
      let row = (cur * RADIX + d) * MASK_WORDS;
      let rank = bits_set(row, word) + countOneBits(atomicLoad(&lane_bits[row + word]) & (bit - 1u));
      let p = next_slot[cur * RADIX + d] + rank;
      keys_out[p] = key;
      values_out[p] = values_in[i];
    }
    // The next round's slots: this round's plus this round's digit counts.
    for (var e = lid; e < RADIX; e += WG) {
      next_slot[(cur ^ 1u) * RADIX + e] = next_slot[cur * RADIX + e] + bits_set((cur * RADIX + e) * MASK_WORDS, MASK_WORDS);
    }
    workgroupBarrier();
    // This round's bitmaps are free again for round k + 2 (round k + 1,
    // on the other half, starts after the next barrier).
    for (var w = lid; w < RADIX * MASK_WORDS; w += WG) {
      atomicStore(&lane_bits[cur * RADIX * MASK_WORDS + w], 0u);
    }
  }
}

// Copies the sorted result back when an in-place sort ran an odd number of
// passes (it ended in scratch); the same coalesced tile layout.
@compute @workgroup_size(WG)
fn copy_back(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= sort.units) {
    return;
  }
  for (var k = 0u; k < ITEMS; k++) {
    let i = t * TILE + k * WG + lid;
    if (i < sort.n) {
      keys_out[i] = keys_in[i];
      values_out[i] = values_in[i];
    }
  }
}
