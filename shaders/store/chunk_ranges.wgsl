// Per block of the changed chunks (list[0 .. changed)): its [min, max] over
// the finite decoded values inside the level (as block_ranges.wgsl), or the
// empty range [FLT_MAX, -FLT_MAX] if its chunk is not resident, so no
// isovalue makes it (or, through the neighbourhood ranges, its neighbours'
// view of it) active. The block also leaves the block cache if it was there:
// its slot becomes empty, so a cached copy never outlives the chunk's bytes
// (a chunk put again may hold other bytes). Needs the zfp decode core,
// chunk_params.wgsl, chunk_blocks.wgsl and the grid snippet.

@group(1) @binding(0) var<storage, read> update_list: array<u32>;
@group(1) @binding(1) var<storage, read_write> block_ranges: array<vec2f>;
@group(1) @binding(2) var<storage, read_write> block_to_slot: array<u32>;
@group(1) @binding(3) var<storage, read_write> slot_to_block: array<u32>;
@group(1) @binding(4) var<storage, read_write> slot_age: array<u32>;
@group(1) @binding(5) var<storage, read_write> cache_counters: array<atomic<u32>>;

const SLOTS_USED_WORD: u32 = 17u;  // C_SLOTS_USED of shaders/isosurface/common.wgsl

@compute @workgroup_size(64)
fn chunk_block_ranges(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                      @builtin(local_invocation_index) lid: u32) {
  let i = linear_workgroup_index(wid, nwg) * 64u + lid;
  if (i >= chunks.changed * chunks.blocks_per_chunk) { return; }
  let chunk = update_list[i / chunks.blocks_per_chunk];
  let c = chunk_block(chunk, i % chunks.blocks_per_chunk);
  if (any(c >= chunks.blocks)) { return; }
  let b = block_index(c);
  let cached = block_to_slot[b];
  if (cached != NO_SLOT) {
    block_to_slot[b] = NO_SLOT;
    slot_to_block[cached] = NO_SLOT;
    slot_age[cached] = NO_SLOT;
    atomicSub(&cache_counters[SLOTS_USED_WORD], 1u);
  }
  var lo = 0x1.fffffep+127f;
  var hi = -0x1.fffffep+127f;
  if (page_table[chunk] != NO_SLOT) {
    var v: array<u32, 64>;
    decode_block(b, &v);
    let o = c * 4u;
    let d = stream.dims;
    let n = min(vec3u(4u), d - o);
    for (var z = 0u; z < n.z; z++) {
      for (var y = 0u; y < n.y; y++) {
        for (var x = 0u; x < n.x; x++) {
          let bits = v[16u * z + 4u * y + x];
          if ((bits & 0x7f800000u) == 0x7f800000u) { continue; }
          let f = bitcast<f32>(bits);
          lo = min(lo, f);
          hi = max(hi, f);
        }
      }
    }
  }
  block_ranges[b] = vec2f(lo, hi);
}
