// classify_blocks: see block_mc_common.wgsl. Needs block_mc_common.wgsl, edge_owner.wgsl.

// ---- classify_blocks
// The slot data as rows of 4 voxels: voxel (x, y, z) of slot s is row s * 16 + y + 4z, component x.
@group(0) @binding(2) var<storage, read> slot_rows: array<vec4f>;
// The counters as a uniform: a storage binding more would pass the default
// limit of 8 per stage (the counters are this pass's indirect arguments too).
@group(1) @binding(0) var<uniform> classify_counters: array<vec4u, 16>;
// Occupied blocks of this surface (cleared before the pass, then copied to
// counters[C_OCCUPIED]: the counters are this pass's indirect arguments, so
// they cannot be bound writable here).
@group(1) @binding(3) var<storage, read_write> occupied_count: atomic<u32>;
@group(1) @binding(1) var<storage, read_write> slot_mc: array<u32>;         // per slot and row (y, z): 4 case bytes, then the row base (expand_cells)
// Per active entry, in three regions of count_stride words (one binding, so
// a chunk pool's tables still fit the default of 8 storage buffers per
// stage): triangle corners, owned cut edges (welded vertices), emitting cells.
@group(1) @binding(2) var<storage, read_write> block_counts: array<u32>;

// Inside bits (value >= iso) of row (y, z) of the 5^3 neighbourhood, at bits shift..shift+4.
fn row_bits(slots: ptr<function, array<u32, 8>>, y: u32, z: u32, shift: u32) -> u32 {
  let d = 2u * (y >> 2u) + 4u * (z >> 2u);
  let row = (y & 3u) + 4u * (z & 3u);
  let iso = volume.iso;
  var bits = 0u;
  let s0 = (*slots)[d];
  if (s0 != NONE) {
    let v = slot_rows[s0 * 16u + row];
    bits = select(0u, 1u, v.x >= iso) | select(0u, 2u, v.y >= iso) | select(0u, 4u, v.z >= iso) | select(0u, 8u, v.w >= iso);
  }
  let s1 = (*slots)[d + 1u];
  if (s1 != NONE) {
    bits |= select(0u, 16u, slot_rows[s1 * 16u + row].x >= iso);
  }
  return bits << shift;
}

// Bits x, x+1 of a 5-bit row into byte x, for x = 0..3.
fn spread_pairs(v: u32) -> u32 {
  return (v & 3u) | ((v & 6u) << 7u) | ((v & 12u) << 14u) | ((v & 24u) << 21u);
}

// Bit 0 of each byte of v that is 0 (exact per byte: no borrow between bytes).
fn zero_bytes(v: u32) -> u32 {
  let y = (v & 0x7f7f7f7fu) + 0x7f7f7f7fu;
  return (~(y | v | 0x7f7f7f7fu)) >> 7u;
}

@compute @workgroup_size(64)
fn classify_blocks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                   @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= classify_counters[C_ACTIVE_GATED >> 2u][C_ACTIVE_GATED & 3u]) {
    return;
  }
  let b = active_ids[i];
  let c = block_coords(b, volume.grid);
  // A ghost or skirt chunk's block (block_mc_common.wgsl): it keeps the
  // cells on its chunk's lower faces (and a skirt's layers 0 and 1 on its
  // axes next to a drawn chunk) that own a cut edge, for their vertices; a
  // ghost's make no triangle, a skirt's only those of layer 0 on such axes.
  let role = block_role(b);
  let lent = role == ROLE_GHOST || role == ROLE_SKIRT;
  let first_in_chunk = block_first_in_chunk(c);
  // (a branch, not select: select evaluates both, and most blocks are not a skirt's)
  var skirt = vec3<bool>(false);
  if (role == ROLE_SKIRT) {
    skirt = skirt_axes(c);
  }
  // Neighbours in chunks not resident or idle: never read, and the cells
  // whose edges' owners may touch them make no triangle (cells_without_indices).
  let unavailable = unavailable_blocks(c, volume.grid);
  // The 8 blocks the cells of b touch (d = dx + 2dy + 4dz); `missing` has bit d
  // set for those not cached (or outside the grid, or unavailable).
  var slots: array<u32, 8>;
  var missing = 0u;
  for (var d = 0u; d < 8u; d++) {
    let s = select(neighbour_slot(c, mc_corner_offset(d)), NONE, ((unavailable >> d) & 1u) != 0u);
    slots[d] = s;
    missing |= select(0u, 1u << d, s == NONE);
  }
  // blocked: bit r set when a cell reaching the neighbours r (bit 0: x = 3,
  // bit 1: y = 3, bit 2: z = 3) touches a missing block, i.e. a missing d
  // with d a non-empty subset of r.
  var blocked = 0u;
  for (var r = 1u; r < 8u; r++) {
    blocked |= select(0u, 1u << r, (missing & blocks_reached(r)) != 0u);
  }
  // Cells inside the volume: l < ext on each axis (dims - 4c >= 1).
  let ext = min(vec3u(4u), volume.dims - c * 4u - 1u);
  // Inside bits of the 5^3 neighbourhood, layer z at bits x + 5y.
  var layers: array<u32, 5>;
  for (var z = 0u; z < 5u; z++) {
    var layer = 0u;
    for (var y = 0u; y < 5u; y++) {
      layer |= row_bits(&slots, y, z, 5u * y);
    }
    layers[z] = layer;
  }
  var indices = 0u;
  var vertices = 0u;
  var cells = 0u;
  // Most active blocks have no sign change at all (their neighbourhood range
  // covers iso, their own voxels do not): all 125 bits equal, nothing to mesh.
  let any_inside = (layers[0] | layers[1] | layers[2] | layers[3] | layers[4]) != 0u;
  let all_inside = (layers[0] & layers[1] & layers[2] & layers[3] & layers[4]) == 0x1ffffffu;
  let mixed = any_inside && !all_inside;
  // The bytes of cells x < ext.x in a row.
  let columns = select((1u << (8u * ext.x)) - 1u, 0xffffffffu, ext.x >= 4u);
  for (var z = 0u; z < 4u; z++) {
    let lower = layers[z];
    let upper = layers[z + 1u];
    for (var y = 0u; y < 4u; y++) {
      var word = 0u;
      if (mixed && z < ext.z && y < ext.y) {
        // The 4 cases of the row at once: byte x gets bits x, x+1 of each of
        // the 4 rows of 5 inside bits around it (corners 0-1, 2-3, 4-5, 6-7).
        let s = 5u * y;
        word = spread_pairs((lower >> s) & 31u) | (spread_pairs((lower >> (s + 5u)) & 31u) << 2u) |
          (spread_pairs((upper >> s) & 31u) << 4u) | (spread_pairs((upper >> (s + 5u)) & 31u) << 6u);
        let r = select(0u, 2u, y == 3u) | select(0u, 4u, z == 3u);
        let unblocked = select(0x00ffffffu, 0u, ((blocked >> r) & 1u) == 1u) | select(0xff000000u, 0u, ((blocked >> (r | 1u)) & 1u) == 1u);
        word &= columns & unblocked;
        // every case but 0 and 255 has triangles: clear the 255 bytes
        word &= ~(zero_bytes(~word) * 255u);
        if (lent) {
          word &= lent_cells_kept(first_in_chunk, skirt, y, z);
        }
        // Cells without indices (a ghost's, a skirt's but its layer next to a
        // drawn chunk, or next to an unavailable chunk) stay only when they
        // own a cut edge (the others would write nothing).
        let without = row_without_indices(role, skirt, unavailable, y, z);
        if (without != 0u) {
          word &= ~(without & (zero_bytes(owned_cut_per_cell(word, c * 4u + vec3u(0u, y, z), volume.dims)) * 255u));
        }
        if (word != 0u) {
          let with_indices = word & ~without;
          for (var x = 0u; x < 4u; x++) {
            indices += case_vertex_count((with_indices >> (8u * x)) & 255u);
          }
          cells += 4u - countOneBits(zero_bytes(word));
        }
      }
      slot_mc[32u * slots[0] + 2u * (y + 4u * z)] = word;
      if (word != 0u) {
        vertices += owned_vertices_of_row(word, c * 4u + vec3u(0u, y, z), volume.dims);
      }
    }
  }
  let stride = count_stride(classify_counters[C_SLOTS >> 2u][C_SLOTS & 3u]);
  block_counts[i] = indices;
  block_counts[stride + i] = vertices;
  block_counts[2u * stride + i] = cells;
  if (indices > 0u) {
    atomicAdd(&occupied_count, 1u);
  }
}

