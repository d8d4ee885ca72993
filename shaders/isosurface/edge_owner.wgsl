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
// vertex of each row of 4 cells (per-slot row bases, expand_cells).
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

// Vertices owned by the cells x < `upto` of a row (4 case bytes in `word`)
// whose cell x = 0 is at global grid point g0, plus, of cell `upto` (when
// < 4), its owned cut edges in `edge_bits` (a mask of edges to count there).
fn owned_vertices_before(word: u32, upto: u32, edge_bits: u32, g0: vec3u, dims: vec3u) -> u32 {
  // A row with no cell on the volume's upper faces: every cell owns edges 0,
  // 4 and 8 only, so count them for the 4 case bytes at once (bit 0 of each
  // byte: corner 0 differs from corner 1, 2 or 4).
  if (g0.y + 2u != dims.y && g0.z + 2u != dims.z && g0.x + 5u < dims.x) {
    let cut0 = (word ^ (word >> 1u)) & 0x01010101u;
    let cut4 = (word ^ (word >> 2u)) & 0x01010101u;
    let cut8 = (word ^ (word >> 4u)) & 0x01010101u;
    let below = select((1u << (8u * upto)) - 1u, 0xffffffffu, upto >= 4u);
    // at most 3 per byte: the byte sums do not carry
    var k = (((cut0 + cut4 + cut8) & below) * 0x01010101u) >> 24u;
    if (upto < 4u) {
      let at = 8u * upto;
      k += select(0u, (cut0 >> at) & 1u, (edge_bits & 1u) != 0u) + select(0u, (cut4 >> at) & 1u, (edge_bits & 0x10u) != 0u) +
        select(0u, (cut8 >> at) & 1u, (edge_bits & 0x100u) != 0u);
    }
    return k;
  }
  var k = 0u;
  for (var x = 0u; x < min(upto + 1u, 4u); x++) {
    let code = (word >> (8u * x)) & 255u;
    let mask = select(0xfffu, edge_bits, x == upto);
    k += countOneBits(owned_edges(last_cell_axes(g0 + vec3u(x, 0u, 0u), dims)) & mc_cut_edges(code) & mask);
  }
  return k;
}

// Vertices a row of cells owns (the row's share of its block's count).
fn owned_vertices_of_row(word: u32, g0: vec3u, dims: vec3u) -> u32 {
  return owned_vertices_before(word, 4u, 0u, g0, dims);
}
