// Decodes a GPU list of blocks into cache slots: entry i < count decodes block
// block_ids[i] into slot slot_ids[i] (64 values, x + 4y + 16z). Dispatched
// indirectly (IndirectArgs, shaders/primitives/indirect_args.wgsl: a 1D, 2D
// or 3D grid, count in dispatch_args[3]) once per stream (or pool) shard;
// entries whose block is in another shard, or in no resident chunk, are skipped.
// The emulator path (each lane stores its own block); decode_blocks_tiled.wgsl
// is the GPU path (coalesced stores through workgroup memory).

@group(1) @binding(0) var<storage, read> block_ids: array<u32>;
@group(1) @binding(1) var<storage, read> slot_ids: array<u32>;
@group(1) @binding(2) var<storage, read> dispatch_args: array<u32>;
@group(1) @binding(3) var<storage, read_write> slots: array<u32>;

@compute @workgroup_size(64)
fn decode_blocks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= dispatch_args[3]) { return; }
  let b = block_ids[i];
  if (!block_in_shard(b)) { return; }
  var q: array<i32, 64>;
  let emax = decode_block_ints(b, &q);
  let base = slot_ids[i] * 64u;
  for (var j = 0u; j < 64u; j++) { slots[base + j] = int_to_float_bits(q[j], emax); }
}
