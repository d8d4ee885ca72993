// Block ranges after chunks arrived in (or left) a pool's slots: entry i
// covers block i % blocks_per_chunk of entry i / blocks_per_chunk of the
// list, (slot, chunk): the chunk that arrived in or left that slot. A chunk
// still in its slot gets its blocks' decoded ranges (block_value_range_at, in
// the pool shard holding the slot); a slot left empty gets the empty range,
// so none of its blocks is ever active; a slot that holds another chunk now
// is that chunk's entry's to write. Ranges are indexed by pool id (slot * B
// + block in chunk). Composed after block_ranges.wgsl (its `ranges` binding
// and range function).

struct ChunkListParams {
  count: u32,             // entries in chunk_list
  blocks_per_chunk: u32,  // (C / 4)^3
  _pad0: u32,
  _pad1: u32,
}

@group(1) @binding(1) var<storage, read> chunk_list: array<vec2u>;
@group(1) @binding(2) var<uniform> chunk_params: ChunkListParams;

@compute @workgroup_size(64)
fn chunk_block_ranges(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                      @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= chunk_params.count * chunk_params.blocks_per_chunk) { return; }
  let entry = chunk_list[i / chunk_params.blocks_per_chunk];
  let slot = entry.x;
  let chunk = entry.y;
  if (slot < pool.first_slot || slot >= pool.end_slot) { return; }  // another shard's dispatch
  let now = slot_table_chunk(slot);
  if (now != chunk && now != POOL_NONE) { return; }  // the slot holds another chunk now: its own entry
  let local = i % chunk_params.blocks_per_chunk;
  let b = slot * chunk_params.blocks_per_chunk + local;
  var r = vec2f(0x1.fffffep+127f, -0x1.fffffep+127f);
  let cb = pool.chunk_blocks;
  let g = pool.chunk_grid;
  let cc = vec3u(chunk % g.x, (chunk / g.x) % g.y, chunk / (g.x * g.y));
  let c = cc * cb + vec3u(local % cb, (local / cb) % cb, local / (cb * cb));
  if (now == chunk && all(c < stream.blocks)) {
    r = block_value_range_at(b, c);
  }
  ranges[2u * b] = r.x;
  ranges[2u * b + 1u] = r.y;
}
