// Naive data-parallel marching cubes over a whole decompressed volume (the
// paper's section 3.3.3 baseline, src/mc/naive-gpu.ts): one invocation per
// cell marks the active cells; after a scan and a compaction of their IDs,
// one invocation per active cell counts its vertices, and after a scan of the
// counts, one invocation per active cell writes its triangles. Same case
// table, corner/edge numbering and interpolation as every MC of the project
// (src/mc/README.md). Composed after shaders/common/grid.wgsl and case_table.wgsl.

struct Params {
  // Grid points per axis (x fastest in `volume`).
  dims: vec3u,
  iso: f32,
  // Cells per axis (dims - 1).
  cells: vec3u,
  cell_count: u32,
  // Vertices `positions` holds (3 f32 each).
  vertex_capacity: u32,
  _pad0: u32,
  _pad1b: u32,
  _pad1: u32,
}

// Counters: [0] active cells (scan total), [1] vertices (scan total).
const ACTIVE_WORD: u32 = 0u;

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> volume: array<f32>;
@group(0) @binding(2) var<storage, read> mc_table: array<u32>;

// Grid point index of cell (i, j, k)'s corner 0, and the 8 corner values.
fn load_corners(cell: vec3u) -> array<f32, 8> {
  let sx = params.dims.x;
  let sxy = sx * params.dims.y;
  let b = cell.x + sx * cell.y + sxy * cell.z;
  return array<f32, 8>(
    volume[b], volume[b + 1u], volume[b + sx], volume[b + sx + 1u],
    volume[b + sxy], volume[b + sxy + 1u], volume[b + sxy + sx], volume[b + sxy + sx + 1u],
  );
}

// Case index of cell (i, j, k), corners compared without a private array.
fn cell_case(cell: vec3u) -> u32 {
  let sx = params.dims.x;
  let sxy = sx * params.dims.y;
  let b = cell.x + sx * cell.y + sxy * cell.z;
  let t = params.iso;
  return select(0u, 1u, volume[b] >= t) | select(0u, 2u, volume[b + 1u] >= t) |
    select(0u, 4u, volume[b + sx] >= t) | select(0u, 8u, volume[b + sx + 1u] >= t) |
    select(0u, 16u, volume[b + sxy] >= t) | select(0u, 32u, volume[b + sxy + 1u] >= t) |
    select(0u, 64u, volume[b + sxy + sx] >= t) | select(0u, 128u, volume[b + sxy + sx + 1u] >= t);
}

fn cell_of(index: u32) -> vec3u {
  let cx = params.cells.x;
  let cy = params.cells.y;
  let row = index / cx;
  return vec3u(index - row * cx, row % cy, row / cy);
}

fn case_words(c: u32) -> vec2u {
  return vec2u(mc_table[2u * c], mc_table[2u * c + 1u]);
}

// ---- mark_active: mask[cell] = 1 when the cell emits triangles (direct 2D grid over all cells)

@group(1) @binding(0) var<storage, read_write> mask: array<u32>;

@compute @workgroup_size(WG)
fn mark_active(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u, @builtin(local_invocation_index) lid: u32) {
  let index = grid_invocation_index(wid, nwg, lid, WG);
  if (index >= params.cell_count) {
    return;
  }
  mask[index] = select(0u, 1u, mc_case_triangles(case_words(cell_case(cell_of(index)))) != 0u);
}

// ---- count_vertices / emit_vertices: one invocation per active cell (indirect grid)

@group(1) @binding(0) var<storage, read> counters: array<u32>;
@group(1) @binding(1) var<storage, read> active_ids: array<u32>;
@group(1) @binding(2) var<storage, read_write> vertex_counts: array<u32>;

@compute @workgroup_size(WG)
fn count_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u, @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, WG);
  if (i >= counters[ACTIVE_WORD]) {
    return;
  }
  vertex_counts[i] = 3u * mc_case_triangles(case_words(cell_case(cell_of(active_ids[i]))));
}

@group(1) @binding(3) var<storage, read> vertex_offsets: array<u32>;
@group(1) @binding(4) var<storage, read_write> positions: array<f32>;

@compute @workgroup_size(WG)
fn emit_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u, @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, WG);
  if (i >= counters[ACTIVE_WORD]) {
    return;
  }
  let cell = cell_of(active_ids[i]);
  var corners = load_corners(cell);
  let words = case_words(mc_case_index(corners, params.iso));
  let n = 3u * mc_case_triangles(words);
  let first = vertex_offsets[i];
  // A surface larger than the buffer writes nothing here; the host sees the
  // total (counters[1]) above the capacity, grows the buffer and runs this pass again.
  if (first + n > params.vertex_capacity) {
    return;
  }
  for (var j = 0u; j < n; j++) {
    let e = mc_case_edge(words, j);
    let p = mc_edge_vertex(cell, e, corners[mc_edge_lower(e)], corners[mc_edge_upper(e)], params.iso);
    let o = 3u * (first + j);
    positions[o] = p.x;
    positions[o + 1u] = p.y;
    positions[o + 2u] = p.z;
  }
}
