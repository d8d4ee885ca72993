// Welded output: one vertex per cut edge of the volume, written by the one
// cell that owns the edge, and an index per triangle corner. The owner of an
// edge is the cell whose corner 0 is the edge's lower end; on the volume's
// upper faces, where that cell does not exist, it is the cell below it on
// those axes (its corner 1, 2, 4, 3, 5 or 6 is then the lower end). So each
// edge has exactly one owner, and a cut edge's owner always emits (the edge's
// ends are two of its corners).
//
// The owner numbers the vertices of its owned cut edges in edge order. A
// block numbers its cells' vertices in cell order (x fastest), from the first
// vertex of each row of 4 cells (per-slot row bases, expand_cells, stored
// beside the row's 4 case bytes so one 8-byte read gets both).
// Needs shaders/mc/case_table.wgsl (corner and edge numbering).

// Bit e set when edge e of a cell with case `code` is cut (its two corners differ).
fn mc_cut_edges(code: u32) -> u32 {
  let dx = code ^ (code >> 1u); // x edges 0..3: lower corners 0, 2, 4, 6
  let dy = code ^ (code >> 2u); // y edges 4..7: lower corners 0, 1, 4, 5
  let dz = code ^ (code >> 4u); // z edges 8..11: lower corners 0, 1, 2, 3
  return (dx & 1u) | ((dx >> 1u) & 2u) | ((dx >> 2u) & 4u) | ((dx >> 3u) & 8u) | ((dy & 3u) << 4u) | ((dy & 0x30u) << 2u) |
    ((dz & 15u) << 8u);
}

// Corner bits (x 1, y 2, z 4) of the axes on which the cell at global grid
// point g is the volume's last cell.
fn last_cell_axes(g: vec3u, dims: vec3u) -> u32 {
  let last = g + vec3u(2u) == dims;
  return select(0u, 1u, last.x) | select(0u, 2u, last.y) | select(0u, 4u, last.z);
}

// Edges the cell owns, from last_cell_axes: its three edges from corner 0,
// plus those of its faces on the volume's upper boundary that no cell above owns.
fn owned_edges(last: u32) -> u32 {
  let x = (last & 1u) != 0u;
  let y = (last & 2u) != 0u;
  let z = (last & 4u) != 0u;
  return 0x111u | select(0u, 0x220u, x) | select(0u, 0x402u, y) | select(0u, 0x044u, z) | select(0u, 0x800u, x && y) |
    select(0u, 0x080u, x && z) | select(0u, 0x008u, y && z);
}

// Edge index of the edge along `axis` from corner `corner` (whose bit on
// `axis` is 0): the inverse of mc_edge_axis / mc_edge_lower.
fn mc_edge_of(axis: u32, corner: u32) -> u32 {
  let yz = corner >> 1u;
  let xz = (corner & 1u) | ((corner >> 1u) & 2u);
  let xy = corner & 3u;
  return 4u * axis + select(select(xy, xz, axis == 1u), yz, axis == 0u);
}

// Bit 0 of each byte of a row's 4 case bytes: edge (a, b) of that cell is cut.
fn row_cut(word: u32, a: u32, b: u32) -> u32 {
  return ((word >> a) ^ (word >> b)) & 0x01010101u;
}

// Vertices owned by the cells x < `upto` of a row (4 case bytes in `word`)
// whose cell x = 0 is at global grid point g0, plus, of cell `upto` (when
// < 4), its owned cut edges in `edge_bits` (a mask of edges to count there;
// 0 when upto is 4).
// Without branches or loops, the volume's upper faces included: the emit pass
// calls it per triangle corner, and a rarely taken general path (the former
// per-cell loop for rows on the upper faces) cost about 5% of a surface on
// SwiftShader even where no lane took it.
fn owned_vertices_before(word: u32, upto: u32, edge_bits: u32, g0: vec3u, dims: vec3u) -> u32 {
  let per_cell = owned_cut_per_cell(word, g0, dims);
  let x_last = dims.x - 2u - g0.x;
  let below = select((1u << (8u * upto)) - 1u, 0xffffffffu, upto >= 4u);
  // cell `upto` itself (edge_bits is 0 when upto is 4)
  let last = select(0u, 1u, upto == x_last) | select(0u, 2u, g0.y + 2u == dims.y) | select(0u, 4u, g0.z + 2u == dims.z);
  let own = countOneBits(owned_edges(last) & mc_cut_edges((word >> ((8u * upto) & 31u)) & 255u) & edge_bits);
  return (((per_cell & below) * 0x01010101u) >> 24u) + own;
}

// Owned cut edges per cell of a row (4 case bytes in `word`, cell x = 0 at
// global grid point g0), in byte x: at most 12 per byte, so no carries.
// Every cell owns edges 0, 4, 8; cells on the upper faces more
// (owned_edges): edges 1, 10 on the last y, 2, 6 on the last z, 3 on both;
// the last x adds 5, 9, then 11 with the last y, 7 with the last z.
fn owned_cut_per_cell(word: u32, g0: vec3u, dims: vec3u) -> u32 {
  let y = select(0u, 0xffffffffu, g0.y + 2u == dims.y);
  let z = select(0u, 0xffffffffu, g0.z + 2u == dims.z);
  // the byte of the cell on the volume's last x (none when it is not in this row)
  let x_last = dims.x - 2u - g0.x;
  let x = select(0u, 255u << ((8u * x_last) & 31u), x_last < 4u);
  let per_cell = row_cut(word, 0u, 1u) + row_cut(word, 0u, 2u) + row_cut(word, 0u, 4u) +
    (y & (row_cut(word, 2u, 3u) + row_cut(word, 2u, 6u))) + (z & (row_cut(word, 4u, 5u) + row_cut(word, 4u, 6u))) +
    (y & z & row_cut(word, 6u, 7u));
  return per_cell + (x & (row_cut(word, 1u, 3u) + row_cut(word, 1u, 5u) + (y & row_cut(word, 3u, 7u)) + (z & row_cut(word, 5u, 7u))));
}

// Vertices a row of cells owns (the row's share of its block's count).
fn owned_vertices_of_row(word: u32, g0: vec3u, dims: vec3u) -> u32 {
  return owned_vertices_before(word, 4u, 0u, g0, dims);
}

// The blocks d (bits, d = dx + 2dy + 4dz) that cells on the +faces r reach:
// the non-empty subsets of r; byte r of (0x0e040200, 0xfe543210).
fn blocks_reached(r: u32) -> u32 {
  return (select(0x0e040200u, 0xfe543210u, r >= 4u) >> (8u * (r & 3u))) & 255u;
}

// The cells of row (y, z) of a block (byte x: 255) whose triangles could use
// a vertex owned by a cell touching one of the neighbour blocks `unavailable`
// (unavailable_blocks: not resident, or idle). Such an owner is not meshed,
// so these cells make no triangle; they keep the vertices they own (a cell
// whose own blocks are all there may own a vertex other cells use). The
// owners of a cell's edges (its corners' cells) touch the grid points
// g + {0, 1, 2} of its lowest corner g, so the blocks of the axes where the
// cell's block-local coordinate is 2 or 3.
fn cells_without_indices(unavailable: u32, y: u32, z: u32) -> u32 {
  let r = select(0u, 2u, y >= 2u) | select(0u, 4u, z >= 2u);
  let low = select(0u, 0x0000ffffu, (unavailable & blocks_reached(r)) != 0u);
  let high = select(0u, 0xffff0000u, (unavailable & blocks_reached(r | 1u)) != 0u);
  return low | high;
}

// Chunk roles (block_mc_common.wgsl), per row (y, z) of a block, byte x 255
// for cell x. The cells of a ghost or skirt chunk's block whose case stays:
// those on the chunk's lower faces (first: block_first_in_chunk), the only
// ones a drawn neighbour's cells index, and a skirt's layers 0 and 1 on its
// axes `skirt` (skirt_axes): the owners of its emitting cells' edges there
// (the others are on the lower faces of its neighbours above).
fn lent_cells_kept(first: vec3<bool>, skirt: vec3<bool>, y: u32, z: u32) -> u32 {
  let rows = (first.y && y == 0u) || (first.z && z == 0u) || (skirt.y && y <= 1u) || (skirt.z && z <= 1u);
  return select(select(0u, 255u, first.x) | select(0u, 0xffffu, skirt.x), 0xffffffffu, rows);
}

// The cells of row (y, z) of a block of a chunk with role `role` that make
// no triangle: every cell of a ghost's; a skirt's but those of chunk-local
// coordinate 0 on its axes `skirt`; and of the rest, those whose edges'
// owners may touch an unavailable neighbour (cells_without_indices).
fn row_without_indices(role: u32, skirt: vec3<bool>, unavailable: u32, y: u32, z: u32) -> u32 {
  let skirt_emits = select(select(0u, 255u, skirt.x), 0xffffffffu, (skirt.y && y == 0u) || (skirt.z && z == 0u));
  let emits = select(select(0u, skirt_emits, role == ROLE_SKIRT), 0xffffffffu, role == ROLE_DRAWN);
  return ~emits | cells_without_indices(unavailable, y, z);
}
