// Block marching cubes over the active blocks, in work proportional to the
// surface (src/isosurface/README.md):
//   classify_blocks  one invocation per active block: the inside bits of its
//                    5^3 neighbourhood (block + its +x/+y/+z neighbour
//                    voxels), every cell's case once; writes the block's
//                    case codes (64 bytes, per slot), index count, welded
//                    vertex count and emitting-cell count
//   (scans of the three give each block's first index, vertex and cell)
//   expand_cells     one invocation per active block with emitting cells:
//                    writes each emitting cell's record (entry, cell) and
//                    first index into the cell list, and the block's row
//                    bases of the welded numbering (edge_owner.wgsl)
//   emit_surface     one invocation per emitting cell (of one index shard):
//                    its corners, the vertices of the cut edges it owns,
//                    the indices of its triangles
// No workgroup memory, no barriers, no atomics but the occupied-block counter:
// nothing depends on the workgroup size, the subgroup size or the scheduling.
//
// Which cells may emit: cell (i, j, k) of the volume is meshed iff it is inside
// the volume (i + 1 < nx, ...; so zfp's padding in partial blocks is never
// used) and every block it touches is cached. That is exact: a cell with a
// sign change makes every block it touches active (active_blocks.wgsl), and
// all active blocks are cached; a cell touching an uncached block therefore
// has no sign change and emits nothing anyway. Voxels of uncached neighbours
// are never read.
//
// A pool's chunks (ChunkedVolume; a stream has every block, all drawn): a
// cell belongs to the chunk holding its lowest corner. A neighbour block in a
// chunk that is not resident or is idle (setRoles) is "unavailable"
// (unavailable_blocks in blocks_*.wgsl): never read, and a cell touching one
// is blocked as if it were not cached. A cell's edges are numbered by their
// owners (edge_owner.wgsl), the cells at its corners, which may touch one
// block more along each axis (grid points g + 2) than the cell does; when
// such a block is unavailable the owner is blocked, so the cell keeps its
// case and the vertices it owns but makes no triangle
// (cells_without_indices). Without this, a chunk resident without its
// +x/+y/+z neighbours would index vertices nobody wrote.
// Roles: a drawn chunk's cells are as above; an idle chunk's blocks are
// never active (mark_active_groups); a ghost chunk's blocks are active by
// the usual rule (drawn cells read their voxels), but its cells make no
// triangle, and classify keeps the case only of those on the chunk's three
// lower faces (chunk-local coordinate 0 on some axis): the only ghost-owned
// vertices a drawn cell can index (a drawn cell's edge owned by a cell of
// another chunk has its lower end on that chunk's lower face). A skirt
// chunk G is a ghost whose cells of chunk-local coordinate 0 on an axis a
// whose G - e_a is resident and drawn (skirt_axes, once per block) make
// triangles too, as a drawn chunk's; it keeps the cases of its layers 0
// and 1 on such an axis as well (the owners of those cells' edges inside
// G; the others lie on the lower faces of G's neighbours above). Its other
// cells are a ghost's (lent_cells_kept, row_without_indices in
// edge_owner.wgsl).
// A cell without indices is kept only when it owns a cut edge; every other
// case byte is cleared in classify, so expand and emit, which read the
// stored bytes, number the vertices as classify counted them. Such cells
// are in the cell list flagged CELL_NO_INDICES, with the first index of the
// cell after them (plan_vertices gives each to exactly one shard).
//
// This file: the bindings and helpers classify_blocks (block_classify.wgsl)
// and emit_surface (block_emit.wgsl) share. Each kernel is its own module, so
// no two resource variables of a module share a binding.
// Needs common.wgsl, a block id snippet (blocks_stream.wgsl or blocks_pool.wgsl),
// shaders/common/grid.wgsl, shaders/mc/case_table.wgsl.

// ---- group 0 of classify and emit: the volume and the cache
@group(0) @binding(0) var<uniform> volume: VolumeParams;
// packCaseTable(): case c in words 2c, 2c+1, read as 4 words per vec4.
@group(0) @binding(1) var<uniform> case_table: array<vec4u, 128>;
// @group(0) @binding(2): the slot data, declared by each kernel in the shape it reads.
@group(0) @binding(3) var<storage, read> block_to_slot: array<u32>;
@group(0) @binding(4) var<storage, read> active_ids: array<u32>;

fn case_words(c: u32) -> vec2u {
  let w = case_table[c >> 1u];
  return select(w.xy, w.zw, (c & 1u) == 1u);
}

fn case_vertex_count(c: u32) -> u32 {
  return 3u * mc_case_triangles(case_words(c));
}

fn cell_of(cell: u32) -> vec3u {
  return vec3u(cell & 3u, (cell >> 2u) & 3u, cell >> 4u);
}

// Cache slot of the block at coordinates n, NONE outside the grid, not present (blocks_*.wgsl) or not cached.
fn cached_slot_at(n: vec3u) -> u32 {
  if (any(n >= volume.grid)) {
    return NONE;
  }
  let b = block_at(n, volume.grid);
  if (b == NONE) {
    return NONE;
  }
  return block_to_slot[b];
}

// Slot of block c + d (d in {0, 1}^3), NONE outside the grid or not cached.
fn neighbour_slot(c: vec3u, d: vec3u) -> u32 {
  return cached_slot_at(c + d);
}
