// Block ids of a whole stream (ZfpGpuStream): raster order over the volume's
// block grid, every block present. The other id snippet is blocks_pool.wgsl;
// the kernels see only the functions below, which both define.
// Needs common.wgsl.

// Block coordinates of block b.
fn block_coords(b: u32, grid: vec3u) -> vec3u {
  return block_coords_of(b, grid);
}

// The id of the block at coordinates c (inside the grid), NONE when it is not present.
fn block_at(c: vec3u, grid: vec3u) -> u32 {
  return block_index_of(c, grid);
}

// Block `local` of group g (groups: edge^3 blocks in raster order over the
// group grid), NONE outside the volume.
fn group_block_id(g: u32, local: u32, grid: vec3u, group_grid: vec3u, edge: u32) -> u32 {
  let gc = vec3u(g % group_grid.x, (g / group_grid.x) % group_grid.y, g / (group_grid.x * group_grid.y));
  let c = gc * edge + vec3u(local % edge, (local / edge) % edge, local / (edge * edge));
  if (any(c >= grid)) {
    return NONE;
  }
  return block_index_of(c, grid);
}

// The group of chunk `chunk` (a chunked source's update passes; a stream has no chunks).
fn group_of_chunk(chunk: u32) -> u32 {
  return chunk;
}

// Chunk roles (blocks_pool.wgsl): a stream has no chunks, every block is drawn.
fn block_role(b: u32) -> u32 {
  return ROLE_DRAWN;
}

fn group_role(g: u32) -> u32 {
  return ROLE_DRAWN;
}

// The axes on which block c is its chunk's first: the whole volume is one chunk.
fn block_first_in_chunk(c: vec3u) -> vec3<bool> {
  return c == vec3u(0u);
}

// A stream has no skirt (blocks_pool.wgsl).
fn skirt_axes(c: vec3u) -> vec3<bool> {
  return vec3<bool>(false);
}

// Neighbours of block c not part of the surface (blocks_pool.wgsl): none, every block is present.
fn unavailable_blocks(c: vec3u, grid: vec3u) -> u32 {
  return 0u;
}
