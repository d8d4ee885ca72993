// GPU path of decode_blocks.wgsl (same bindings, same result): entry i < count
// decodes block block_ids[i] into slot slot_ids[i] (64 values, x + 4y + 16z).
// Each invocation still decodes one block, but stages its 64 words in
// workgroup memory; after one barrier the workgroup writes the staged blocks
// out together, consecutive invocations on consecutive words of a slot
// (coalesced stores, where decode_blocks has each lane write 64 words 256
// bytes away from its neighbour's). WG (invocations per workgroup) is a const
// prepended by the host, since it sizes the workgroup arrays.
//
// Workgroup memory: WG * 65 + WG words (8.25 KiB at WG = 32, under WebGPU's
// 16 KiB default). Row stride 65, not 64, so that the decoding lanes, which
// each write word j of their own row, hit different banks.

@group(1) @binding(0) var<storage, read> block_ids: array<u32>;
@group(1) @binding(1) var<storage, read> slot_ids: array<u32>;
@group(1) @binding(2) var<storage, read> dispatch_args: array<u32>;
@group(1) @binding(3) var<storage, read_write> slots: array<u32>;

const STAGE_STRIDE: u32 = 65u;
const NO_SLOT: u32 = 0xffffffffu;  // a slot index no binding can reach (slots are 256 bytes)

var<workgroup> stage: array<u32, WG * STAGE_STRIDE>;
var<workgroup> stage_slot: array<u32, WG>;

@compute @workgroup_size(WG)
fn decode_blocks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, WG);
  // No early return: every invocation must reach the barrier. Lanes past the
  // count, or whose block lies in another shard (or no resident chunk), skip
  // the decode and mark their row empty.
  var slot = NO_SLOT;
  if (i < dispatch_args[3]) {
    let b = block_ids[i];
    if (block_in_shard(b)) {
      slot = slot_ids[i];
      var q: array<i32, 64>;
      let emax = decode_block_ints(b, &q);
      let row = lid * STAGE_STRIDE;
      for (var j = 0u; j < 64u; j++) { stage[row + j] = int_to_float_bits(q[j], emax); }
    }
  }
  stage_slot[lid] = slot;
  workgroupBarrier();
  // WG * 64 staged words, WG at a time: word e of the tile is word e % 64 of row e / 64.
  for (var k = 0u; k < 64u; k++) {
    let e = k * WG + lid;
    let row = e >> 6u;
    let word = e & 63u;
    let s = stage_slot[row];
    if (s != NO_SLOT) { slots[s * 64u + word] = stage[row * STAGE_STRIDE + word]; }
  }
}
