// Block ranges of chunks that arrived in (or left) a pool: entry i covers
// block i % blocks_per_chunk of chunk chunk_list[i / blocks_per_chunk]. A
// resident chunk's blocks get the range of their decoded values
// (block_value_range, in the pool shard holding the chunk); a chunk that is
// not resident gets the empty range, so none of its blocks is ever active.
// Composed after block_ranges.wgsl (its `ranges` binding and range function).

struct ChunkListParams {
  count: u32,             // chunks in chunk_list
  blocks_per_chunk: u32,  // (C / 4)^3
  _pad0: u32,
  _pad1: u32,
}

@group(1) @binding(1) var<storage, read> chunk_list: array<u32>;
@group(1) @binding(2) var<uniform> chunk_params: ChunkListParams;

@compute @workgroup_size(64)
fn chunk_block_ranges(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                      @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= chunk_params.count * chunk_params.blocks_per_chunk) { return; }
  let chunk = chunk_list[i / chunk_params.blocks_per_chunk];
  let local = i % chunk_params.blocks_per_chunk;
  let cb = pool.chunk_blocks;
  let g = pool.chunk_grid;
  let cc = vec3u(chunk % g.x, (chunk / g.x) % g.y, chunk / (g.x * g.y));
  let c = cc * cb + vec3u(local % cb, (local / cb) % cb, local / (cb * cb));
  if (any(c >= stream.blocks)) { return; }
  let b = c.x + stream.blocks.x * (c.y + stream.blocks.y * c.z);
  let slot = page_table[chunk];
  var r = vec2f(0x1.fffffep+127f, -0x1.fffffep+127f);
  if (slot != POOL_NONE) {
    if (slot < pool.first_slot || slot >= pool.end_slot) { return; }  // another shard's dispatch
    r = block_value_range(b);
  }
  ranges[2u * b] = r.x;
  ranges[2u * b + 1u] = r.y;
}
