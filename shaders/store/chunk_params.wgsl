// A pool of compressed chunks (src/store/chunked-volume.ts): every chunk of
// a level is a zfp stream with its header, chunk_words 32-bit words long, at
// slot * chunk_words of the pool; page_table[chunk] is its slot (NONE = not
// resident). Chunks are edge_blocks^3 blocks, in raster order over `grid`.

struct ChunkParams {
  blocks: vec3u,          // blocks of the level per axis
  block_count: u32,
  grid: vec3u,            // chunks per axis
  edge_blocks: u32,       // chunk edge / 4
  chunk_words: u32,       // bytes of one chunk / 4 (a multiple of 2: zfp pads to 64 bits)
  header_bits: u32,       // 96 or 148: where block 0 of a chunk starts
  blocks_per_chunk: u32,  // edge_blocks^3
  changed: u32,           // entries of the changed-chunk list (update kernels)
  dilated: u32,           // entries of the dilated list, after the changed ones
  pad0: u32,
  pad1: u32,
  pad2: u32,
}

const NO_SLOT: u32 = 0xffffffffu;

@group(0) @binding(2) var<storage, read> page_table: array<u32>;
@group(0) @binding(3) var<uniform> chunks: ChunkParams;

fn chunk_coords_of(chunk: u32) -> vec3u {
  let g = chunks.grid;
  return vec3u(chunk % g.x, (chunk / g.x) % g.y, chunk / (g.x * g.y));
}

fn chunk_of_block(c: vec3u) -> u32 {
  let cc = c / chunks.edge_blocks;
  return cc.x + chunks.grid.x * (cc.y + chunks.grid.y * cc.z);
}

// Block coordinates of block `local` (raster order inside the chunk) of `chunk` (may lie outside the level).
fn chunk_block(chunk: u32, local: u32) -> vec3u {
  let e = chunks.edge_blocks;
  return chunk_coords_of(chunk) * e + vec3u(local % e, (local / e) % e, local / (e * e));
}

fn block_index(c: vec3u) -> u32 {
  return c.x + chunks.blocks.x * (c.y + chunks.blocks.y * c.z);
}
