// GPU path of decode_volume.wgsl (same bindings, same output): decodes blocks
// [range.x, range.y) of the stream (inside this shard) into a float32 volume,
// x fastest, holding z planes from range.z on. Workgroup t (counted from
// range.w) is one tile: TILE consecutive blocks along x of one block row
// (y, z). Each invocation decodes one block into workgroup memory; after one
// barrier the workgroup writes the tile's voxels line by line (16 lines of up
// to 4 * TILE consecutive x voxels), consecutive invocations on consecutive
// voxels (128 contiguous bytes per store step, where decode_volume.wgsl has
// each lane write 4-voxel pieces of lines with a 16-byte stride between lanes).
// Padding of partial blocks at the far faces is decoded but never written.
//
// Workgroup memory: TILE * 64 words = 8 KiB (WebGPU's default limit is 16 KiB;
// TILE = 64 would need all of it). No padding: word j of block k is stored at
// k * 64 + ((j + 4 * (k % 8) + k / 8) % 64), a rotation that puts the decoding
// lanes' stores of word j (k = lane) in 32 different banks and the readers'
// loads (lane l reads word c + l % 4 of block 8 * step + l / 4) in 32
// different banks too.

struct VolumeParams {
  range: vec4u,  // first block, end block, first z plane of the output, first tile
}

@group(1) @binding(0) var<uniform> vparams: VolumeParams;
@group(1) @binding(1) var<storage, read_write> volume_out: array<u32>;

const TILE: u32 = 32u;  // blocks along x per workgroup = invocations per workgroup

var<workgroup> stage: array<u32, 2048>;  // TILE * 64

fn stage_index(k: u32, j: u32) -> u32 {
  return k * 64u + ((j + 4u * (k & 7u) + (k >> 3u)) & 63u);
}

@compute @workgroup_size(32)
fn decode_volume(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let grid = stream.blocks;
  let tiles_x = ceil_div(grid.x, TILE);
  let tile = vparams.range.w + grid_workgroup_index(wid, nwg);
  let row = tile / tiles_x;               // block row: by + grid.y * bz
  let bx0 = (tile % tiles_x) * TILE;       // first block x of the tile
  let first = row * grid.x + bx0;          // its raster block index
  let lo = vparams.range.x;
  let hi = vparams.range.y;
  // No early return: every invocation reaches the barrier. Lanes past the
  // row's end or outside [lo, hi) (other shards, other slabs) skip the decode;
  // their voxels are not written below.
  let b = first + lid;
  if (bx0 + lid < grid.x && b >= lo && b < hi) {
    var q: array<i32, 64>;
    let emax = decode_block_ints(b, &q);
    for (var j = 0u; j < 64u; j++) { stage[stage_index(lid, j)] = int_to_float_bits(q[j], emax); }
  }
  workgroupBarrier();
  if (row >= grid.y * grid.z) { return; }  // overshoot of a 2D grid (uniform)
  let d = stream.dims;
  let x0 = 4u * bx0;
  let xs = min(4u * TILE, d.x - x0);       // voxels along x in this tile
  let y0 = 4u * (row % grid.y);
  let z0 = 4u * (row / grid.y);
  let ny = min(4u, d.y - y0);
  let nz = min(4u, d.z - z0);
  for (var z = 0u; z < nz; z++) {
    for (var y = 0u; y < ny; y++) {
      let line = x0 + d.x * (y0 + y + d.y * (z0 + z - vparams.range.z));
      let word = 16u * z + 4u * y;
      for (var x = lid; x < xs; x += TILE) {
        let k = x >> 2u;
        let bk = first + k;
        if (bk >= lo && bk < hi) { volume_out[line + x] = stage[stage_index(k, word + (x & 3u))]; }
      }
    }
  }
}
