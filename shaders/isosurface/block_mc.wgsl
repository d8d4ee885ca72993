// Block marching cubes: one workgroup of 64 invocations per block, one
// invocation per dual cell (x + 4y + 16z). The workgroup loads the block and
// its +x/+y/+z face, edge and corner neighbour voxels (5 x 5 x 5 values) from
// the cache into workgroup memory, so each value is read from the cache once.
//
// Which cells may emit: cell (i, j, k) of the volume is meshed iff it is inside
// the volume (i + 1 < nx, ...; so zfp's padding in partial blocks is never
// used) and every block it touches is cached. That is exact: a cell with a
// sign change makes every block it touches active (active_blocks.wgsl), and
// all active blocks are cached; a cell touching an uncached block therefore
// has no sign change and emits nothing anyway. Voxels of uncached neighbours
// are not loaded.
//
// Needs common.wgsl, dispatch.wgsl, shaders/mc/case_table.wgsl, vertex_format.wgsl.

@group(0) @binding(0) var<uniform> volume: VolumeParams;
// packCaseTable(): case c in words 2c, 2c+1, read as 4 words per vec4.
@group(0) @binding(1) var<uniform> case_table: array<vec4u, 128>;
@group(0) @binding(2) var<storage, read> slot_data: array<f32>;
@group(0) @binding(3) var<storage, read> block_to_slot: array<u32>;
@group(0) @binding(4) var<storage, read> active_ids: array<u32>;

var<workgroup> voxels: array<f32, 125>;      // (x, y, z) in 0..4 at x + 5y + 25z
var<workgroup> neighbour_cached: array<u32, 8>; // block + (dx, dy, dz) cached, at dx + 2dy + 4dz

// Loads block b's 5^3 neighbourhood; call from every invocation, then barrier.
fn load_block(b: u32, lid: u32) {
  let c = block_coords_of(b, volume.grid);
  for (var s = lid; s < 125u; s += 64u) {
    let v = vec3u(s % 5u, (s / 5u) % 5u, s / 25u);
    let d = v >> vec3u(2u);              // which neighbour: 0 or 1 per axis
    let nc = c + d;
    var slot = NONE;
    if (all(nc < volume.grid)) {
      slot = block_to_slot[block_index_of(nc, volume.grid)];
    }
    var value = 0.0;
    if (slot != NONE) {
      let l = v & vec3u(3u);
      value = slot_data[slot * 64u + l.x + 4u * l.y + 16u * l.z];
    }
    voxels[s] = value;
    // exactly one invocation loads the neighbour's voxel (0, 0, 0)
    if (all((v & vec3u(3u)) == vec3u(0u))) {
      neighbour_cached[d.x + 2u * d.y + 4u * d.z] = select(0u, 1u, slot != NONE);
    }
  }
}

fn cell_of(lid: u32) -> vec3u {
  return vec3u(lid & 3u, (lid >> 2u) & 3u, lid >> 4u);
}

fn voxel(l: vec3u) -> f32 {
  return voxels[l.x + 5u * l.y + 25u * l.z];
}

// Case index of cell `l` of block b, or 0 if the cell may not emit (see top).
fn cell_case(b: u32, l: vec3u) -> u32 {
  let g = block_coords_of(b, volume.grid) * 4u + l;
  if (any(g + 1u >= volume.dims)) {
    return 0u;
  }
  // blocks touched: + (dx, dy, dz) with d <= reach on each axis
  let reach = vec3u(l == vec3u(3u));
  for (var d = 1u; d < 8u; d++) {
    let dd = vec3u(d & 1u, (d >> 1u) & 1u, d >> 2u);
    if (all(dd <= reach) && neighbour_cached[d] == 0u) {
      return 0u;
    }
  }
  var c = 0u;
  for (var q = 0u; q < 8u; q++) {
    c |= select(0u, 1u << q, voxel(l + mc_corner_offset(q)) >= volume.iso);
  }
  return c;
}

fn case_words(c: u32) -> vec2u {
  let w = case_table[c >> 1u];
  return select(w.xy, w.zw, (c & 1u) == 1u);
}

// ---- Pass 1: vertices per active block (0 = not occupied).
@group(1) @binding(0) var<storage, read> count_counters: array<u32>;
@group(1) @binding(1) var<storage, read_write> vertex_counts: array<u32>;
@group(1) @binding(2) var<storage, read_write> occupied_mask: array<u32>;

var<workgroup> block_vertices: atomic<u32>;

@compute @workgroup_size(64)
fn count_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                  @builtin(local_invocation_index) lid: u32) {
  let i = grid_workgroup_index(wid, nwg);
  // The whole workgroup takes the same branch (i is uniform), and the
  // barriers stay in uniform control flow.
  let live = i < count_counters[C_ACTIVE_GATED];
  let b = select(0u, active_ids[min(i, arrayLength(&active_ids) - 1u)], live);
  if (lid == 0u) {
    atomicStore(&block_vertices, 0u);
  }
  if (live) {
    load_block(b, lid);
  }
  workgroupBarrier();
  if (live) {
    let n = 3u * mc_case_triangles(case_words(cell_case(b, cell_of(lid))));
    if (n > 0u) {
      atomicAdd(&block_vertices, n);
    }
  }
  let total = workgroupUniformLoad(&block_vertices);
  if (live && lid == 0u) {
    vertex_counts[i] = total;
    occupied_mask[i] = select(0u, 1u, total > 0u);
  }
}

// ---- Pass 2: the vertices of the occupied blocks reaching one shard.
@group(1) @binding(0) var<storage, read> occupied_list: array<u32>;   // entries of the active list
@group(1) @binding(1) var<storage, read> vertex_offsets: array<u32>;  // exclusive scan of vertex_counts
@group(2) @binding(0) var<storage, read> shard: array<u32, 8>;        // this shard's record (plan.wgsl)
@group(2) @binding(1) var<storage, read_write> shard_vertices: array<vec2u>;

// Per-cell vertex counts (<= 15), eight 4-bit fields per word, for the
// workgroup's exclusive scan: one atomicOr per cell and one barrier, then
// each invocation adds up the fields below its own with a few word operations.
var<workgroup> cell_counts: array<atomic<u32>, 8>;

fn nibble_sum(w: u32) -> u32 {
  let bytes = (w & 0x0f0f0f0fu) + ((w >> 4u) & 0x0f0f0f0fu);  // four sums <= 30
  return (bytes * 0x01010101u) >> 24u;                        // their sum <= 120, no carries
}

@compute @workgroup_size(64)
fn emit_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let w = grid_workgroup_index(wid, nwg);
  let live = w < shard[S_COUNT];
  var entry = 0u;
  if (live) {
    entry = occupied_list[shard[S_FIRST] + w];
  }
  let b = active_ids[entry];
  if (lid < 8u) {
    atomicStore(&cell_counts[lid], 0u);
  }
  if (live) {
    load_block(b, lid);
  }
  workgroupBarrier();
  let l = cell_of(lid);
  var words = vec2u(0u);
  var n = 0u;
  if (live) {
    words = case_words(cell_case(b, l));
    n = 3u * mc_case_triangles(words);
    if (n > 0u) {
      atomicOr(&cell_counts[lid >> 3u], n << (4u * (lid & 7u)));
    }
  }
  workgroupBarrier();
  if (!live || n == 0u) {
    return;
  }
  var first = vertex_offsets[entry];
  for (var k = 0u; k < (lid >> 3u); k++) {
    first += nibble_sum(atomicLoad(&cell_counts[k]));
  }
  let below = (1u << (4u * (lid & 7u))) - 1u;
  first += nibble_sum(atomicLoad(&cell_counts[lid >> 3u]) & below);
  let base = shard[S_BASE];
  let size = arrayLength(&shard_vertices);
  for (var m = 0u; m < n; m++) {
    let v = first + m;
    if (v < base || v - base >= size) {
      continue;
    }
    let e = mc_case_edge(words, m);
    let lo = l + mc_corner_offset(mc_edge_lower(e));
    let v0 = voxel(lo);
    let v1 = voxel(l + mc_corner_offset(mc_edge_upper(e)));
    // the project's interpolation formula (src/mc/README.md), from the lower corner
    let t = (volume.iso - v0) / (v1 - v0);
    var p = vec3f(lo);
    let axis = mc_edge_axis(e);
    p[axis] = p[axis] + t;
    shard_vertices[v - base] = vec2u(encode_vertex_position(p), b);
  }
}
