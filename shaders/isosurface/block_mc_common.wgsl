// Block marching cubes: one workgroup of 64 invocations per block, one
// invocation per dual cell (x + 4y + 16z). This file holds what both ways of
// reading the block's voxels share (block_mc_workgroup.wgsl: through
// workgroup memory; block_mc_direct.wgsl: each invocation reads its corners
// from the cache; see src/isosurface/README.md for when each is used).
//
// Which cells may emit: cell (i, j, k) of the volume is meshed iff it is inside
// the volume (i + 1 < nx, ...; so zfp's padding in partial blocks is never
// used) and every block it touches is cached. That is exact: a cell with a
// sign change makes every block it touches active (active_blocks.wgsl), and
// all active blocks are cached; a cell touching an uncached block therefore
// has no sign change and emits nothing anyway. Voxels of uncached neighbours
// are never read.
//
// Needs common.wgsl, dispatch.wgsl, shaders/mc/case_table.wgsl, vertex_format.wgsl.

@group(0) @binding(0) var<uniform> volume: VolumeParams;
// packCaseTable(): case c in words 2c, 2c+1, read as 4 words per vec4.
@group(0) @binding(1) var<uniform> case_table: array<vec4u, 128>;
@group(0) @binding(2) var<storage, read> slot_data: array<f32>;
@group(0) @binding(3) var<storage, read> block_to_slot: array<u32>;
@group(0) @binding(4) var<storage, read> active_ids: array<u32>;

// Pass 2 (vertices): the occupied blocks reaching one shard.
@group(1) @binding(0) var<storage, read> occupied_list: array<u32>;   // entries of the active list
@group(1) @binding(1) var<storage, read> vertex_offsets: array<u32>;  // exclusive scan of the block vertex counts
@group(2) @binding(0) var<storage, read> shard: array<u32, 8>;        // this shard's record (plan.wgsl)
@group(2) @binding(1) var<storage, read_write> shard_vertices: array<vec2u>;

// A cell's corner values (corner q = x + 2y + 4z) and case (0 if it may not emit).
struct Cell {
  values: array<f32, 8>,
  case_index: u32,
}

fn cell_of(lid: u32) -> vec3u {
  return vec3u(lid & 3u, (lid >> 2u) & 3u, lid >> 4u);
}

fn cell_inside_volume(c: vec3u, l: vec3u) -> bool {
  return all(c * 4u + l + 1u < volume.dims);
}

fn case_of(values: array<f32, 8>) -> u32 {
  var v = values;
  var c = 0u;
  for (var q = 0u; q < 8u; q++) {
    c |= select(0u, 1u << q, v[q] >= volume.iso);
  }
  return c;
}

fn case_words(c: u32) -> vec2u {
  let w = case_table[c >> 1u];
  return select(w.xy, w.zw, (c & 1u) == 1u);
}

fn cell_vertex_count(c: u32) -> u32 {
  return 3u * mc_case_triangles(case_words(c));
}

// Per-cell vertex counts (<= 15) of a block, eight 4-bit fields per word, for
// the workgroup's exclusive scan: one atomicOr per cell and one barrier, then
// each invocation adds up the fields below its own with a few word operations.
var<workgroup> cell_counts: array<atomic<u32>, 8>;

fn nibble_sum(w: u32) -> u32 {
  let bytes = (w & 0x0f0f0f0fu) + ((w >> 4u) & 0x0f0f0f0fu);  // four sums <= 30
  return (bytes * 0x01010101u) >> 24u;                        // their sum <= 120, no carries
}

// Vertices of cells before `lid` in the block (after the barrier that follows the atomicOrs).
fn cells_before(lid: u32) -> u32 {
  var sum = 0u;
  for (var k = 0u; k < (lid >> 3u); k++) {
    sum += nibble_sum(atomicLoad(&cell_counts[k]));
  }
  let below = (1u << (4u * (lid & 7u))) - 1u;
  return sum + nibble_sum(atomicLoad(&cell_counts[lid >> 3u]) & below);
}

// Writes the cell's vertices first.. (global indices) that fall in this shard.
fn emit_cell(cell: Cell, l: vec3u, b: u32, first: u32) {
  var values = cell.values;
  let words = case_words(cell.case_index);
  let n = 3u * mc_case_triangles(words);
  let base = shard[S_BASE];
  let size = arrayLength(&shard_vertices);
  for (var m = 0u; m < n; m++) {
    let v = first + m;
    if (v < base || v - base >= size) {
      continue;
    }
    let e = mc_case_edge(words, m);
    let lower = mc_edge_lower(e);
    let v0 = values[lower];
    let v1 = values[mc_edge_upper(e)];
    // the project's interpolation formula (src/mc/README.md), from the lower corner
    let t = (volume.iso - v0) / (v1 - v0);
    var p = vec3f(l + mc_corner_offset(lower));
    let axis = mc_edge_axis(e);
    p[axis] = p[axis] + t;
    shard_vertices[v - base] = vec2u(encode_vertex_position(p), b);
  }
}
