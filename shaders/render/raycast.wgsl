// The isosurface ray cast in the decompressed block cache (issue 46): no
// triangles. Each pixel's ray enters the volume's box and walks its cells
// (a 3D DDA); a block whose 27-block neighbourhood range excludes the
// isovalue (lo < iso <= hi fails: the active-block rule of
// shaders/isosurface/active_groups.wgsl) is skipped whole, and in the other
// blocks each cell the ray crosses is tested for the first crossing of its
// trilinear interpolant, exactly (shaders/raycast/cell_root.wgsl). Every
// corner of a crossing cell lies in an active block, and the surface's
// computation decoded every active block into the cache (slot_data, 64
// values per slot; block_to_slot): the cache holds what the rays read.
// How blocks are named and which the ray may enter come from a snippet
// composed before this file: ray_blocks_stream.wgsl (a volume opened whole:
// raster ids, every block) or ray_blocks_pool.wgsl (a store's level: pool
// ids through the level's page table; only the regions of the step the
// level owns, so each level of a step is one draw and the depth test keeps
// the nearest level's hit). The coordinates here are the drawn volume's (a
// level's own voxels); uniforms place them in the world.
// The hit is lit as the mesh is (shaders/render/lighting.wgsl), with the
// normal the mesh path computes (the central-difference gradient at the
// cell's corners, interpolated at the hit; the interpolant's own gradient
// where a neighbour voxel is not cached), and writes its depth, so the
// box, other layers and picking composite with it. A hit the clip cuts away
// is passed through (the ray goes on to the next cell).
struct Rays {
  inv_view_proj: mat4x4f,
  dims: vec4i,         // voxels per axis; w: blocks per row (x)
  grid: vec4u,         // blocks per axis
  front: vec4f,        // outside colour; a: ambient
  back: vec4f,         // inside colour; a: specular strength
  extra: vec4f,        // x: rim strength, y: depth cue, z: near, w: far (eye distance)
  voxel_size: vec4f,   // xyz: world size of a voxel; w: the isovalue
  origin: vec4f,       // xyz: where voxel (0, 0, 0) sits, in voxels
  clip_count: vec4u,   // x: planes in use
  clip: array<vec4f, 7>, // world space: kept where dot(xyz, p) + w >= 0 for every plane
  chunk_grid: vec4u,   // a pool: chunks per axis; w: the level's chunk count (where the slot table starts)
  pool: vec4u,         // a pool: x blocks per chunk edge, y cells a level reaches above its own regions (seams)
  region_grid: vec4u,  // a pool: the step's region grid, cells per axis; w: this draw's level
  region_edge: vec4f,  // a pool: a region cell's edge in level-0 voxels
  level_scale: vec4f,  // a pool: level-0 voxels per voxel of this level; w: voxels a coarser level reaches into a finer region
  level_offset: vec4f, // a pool: where this level's voxel 0 lies in level-0 voxels; w: and level-0 voxels more
};
@group(1) @binding(0) var<uniform> rays: Rays;
@group(1) @binding(1) var<storage, read> slot_data: array<f32>;
@group(1) @binding(2) var<storage, read> block_to_slot: array<u32>;
@group(1) @binding(3) var<storage, read> neighbourhood_ranges: array<vec2f>;

const NO_SLOT: u32 = 0xffffffffu;
const NO_BLOCK: u32 = 0xffffffffu;
/** At most this many cells and skipped blocks per ray (a 2048-voxel diagonal walks ~3 x 2048 cells). */
const MAX_STEPS: u32 = 16384u;

struct VsOut {
  @builtin(position) clip: vec4f,
  @location(0) ndc: vec2f,
};

// One triangle over the whole viewport.
@vertex
fn vs(@builtin(vertex_index) i: u32) -> VsOut {
  let xy = vec2f(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
  return VsOut(vec4f(xy, 0.0, 1.0), xy);
}

fn world_of(p: vec3f) -> vec3f {
  return (p + rays.origin.xyz) * rays.voxel_size.xyz;
}

fn ray_clipped(world: vec3f) -> bool {
  for (var i = 0u; i < min(rays.clip_count.x, 7u); i++) {
    let p = rays.clip[i];
    if (dot(p.xyz, world) + p.w < 0.0) {
      return true;
    }
  }
  return false;
}

fn block_active(b: vec3u) -> bool {
  let id = block_id(b);
  if (id == NO_BLOCK) {
    return false;
  }
  let r = neighbourhood_ranges[id];
  let iso = rays.voxel_size.w;
  return r.x < iso && iso <= r.y;
}

// A voxel's decoded value from the cache; false when its block is not cached.
fn voxel(c: vec3u, out_value: ptr<function, f32>) -> bool {
  let id = block_id(c / 4u);
  if (id == NO_BLOCK) {
    return false;
  }
  let slot = block_to_slot[id];
  if (slot == NO_SLOT) {
    return false;
  }
  let r = c % 4u;
  *out_value = slot_data[slot * 64u + r.x + 4u * r.y + 16u * r.z];
  return true;
}

// The 8 corners of the cell at `c` (x fastest); false when one is not cached.
fn cell_corners(c: vec3u, v: ptr<function, array<f32, 8>>) -> bool {
  for (var k = 0u; k < 8u; k++) {
    var x = 0.0;
    if (!voxel(c + vec3u(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u), &x)) {
      return false;
    }
    (*v)[k] = x;
  }
  return true;
}

struct FragOut {
  @location(0) colour: vec4f,
  @builtin(frag_depth) depth: f32,
};

@fragment
fn fs(in: VsOut) -> FragOut {
  // the pixel's ray in voxel coordinates: from the near plane to the far plane
  let near_h = rays.inv_view_proj * vec4f(in.ndc, 0.0, 1.0);
  let far_h = rays.inv_view_proj * vec4f(in.ndc, 1.0, 1.0);
  let o = near_h.xyz / near_h.w / rays.voxel_size.xyz - rays.origin.xyz;
  let d = far_h.xyz / far_h.w / rays.voxel_size.xyz - rays.origin.xyz - o;
  // the box of cells [0, dims - 1]
  let hi = vec3f(rays.dims.xyz - vec3i(1));
  let inv = 1.0 / select(d, vec3f(1e-30), abs(d) < vec3f(1e-30));
  let ta = (vec3f(0.0) - o) * inv;
  let tb = (hi - o) * inv;
  let t_enter = max(max(max(min(ta.x, tb.x), min(ta.y, tb.y)), min(ta.z, tb.z)), 0.0);
  let t_exit = min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z));
  if (!(t_enter < t_exit)) {
    discard;
  }
  let iso = rays.voxel_size.w;
  let last = vec3u(max(rays.dims.xyz - vec3i(2), vec3i(0)));
  // a small step past each boundary in t (the cell's exit is computed exactly; this only picks the next cell)
  let eps = 1e-5 * (t_exit - t_enter) + 1e-7;
  var t = t_enter;
  for (var step = 0u; step < MAX_STEPS && t < t_exit; step++) {
    let p = o + (t + eps) * d;
    let cell = min(vec3u(max(floor(p), vec3f(0.0))), last);
    // the cells around this one where this draw's region (region_box: a store's level owns some of the
    // step's regions) is the same: passed whole when they are not this draw's to trace
    var rlo: vec3f;
    var rhi: vec3f;
    let traced = region_box(cell, &rlo, &rhi);
    let re = select(rlo, rhi, d > vec3f(0.0));
    let tr = (re - o) * inv;
    let t_region = max(min(min(select(1e30, tr.x, d.x != 0.0), select(1e30, tr.y, d.y != 0.0)), select(1e30, tr.z, d.z != 0.0)), t + eps);
    if (!traced) {
      t = t_region;
      continue;
    }
    let block = cell / 4u;
    if (!block_active(block)) {
      // past the block: its box's exit along the ray
      let blo = vec3f(block * 4u);
      let bhi = vec3f(min(block * 4u + 4u, last + vec3u(1u)));
      let e = select(blo, bhi, d > vec3f(0.0));
      let te = (e - o) * inv;
      t = max(min(min(select(1e30, te.x, d.x != 0.0), select(1e30, te.y, d.y != 0.0)), select(1e30, te.z, d.z != 0.0)), t + eps);
      continue;
    }
    let lo_c = vec3f(cell);
    let e = select(lo_c, lo_c + 1.0, d > vec3f(0.0));
    let te = (e - o) * inv;
    let t_cell = max(min(min(min(min(select(1e30, te.x, d.x != 0.0), select(1e30, te.y, d.y != 0.0)), select(1e30, te.z, d.z != 0.0)), t_exit), t_region), t + eps);
    var v: array<f32, 8>;
    if (cell_corners(cell, &v)) {
      var lo = v[0];
      var hi_v = v[0];
      for (var k = 1u; k < 8u; k++) {
        lo = min(lo, v[k]);
        hi_v = max(hi_v, v[k]);
      }
      if (lo <= iso && iso <= hi_v) {
        // cell-local: the ray from the cell's corner; the parameter stays the ray's
        let root = cell_first_crossing(v, iso, o - lo_c, d, t, t_cell);
        if (root >= 0.0) {
          let hit = o + root * d;
          let world = world_of(hit);
          if (!ray_clipped(world)) {
            return lit_hit(v, cell, hit - lo_c, world);
          }
        }
      }
    }
    t = t_cell;
  }
  discard;
  return FragOut(vec4f(0.0), 1.0);
}

// The central-difference gradient at voxel c (one-sided at the volume's
// faces), as the mesh path's vertex normals; false when a neighbour is not cached.
fn voxel_gradient(c: vec3u, out_g: ptr<function, vec3f>) -> bool {
  let top = vec3u(rays.dims.xyz - vec3i(1));
  var g = vec3f(0.0);
  for (var a = 0u; a < 3u; a++) {
    var e = vec3u(0u);
    e[a] = 1u;
    let lo = select(c - e, c, c[a] == 0u);
    let hi = select(c + e, c, c[a] == top[a]);
    var x0 = 0.0;
    var x1 = 0.0;
    if (!voxel(lo, &x0) || !voxel(hi, &x1)) {
      return false;
    }
    g[a] = (x1 - x0) / max(f32(hi[a] - lo[a]), 1.0);
  }
  *out_g = g;
  return true;
}

// The gradient at a point of the cell: the corners' central differences
// interpolated trilinearly; the interpolant's own gradient when a neighbour is missing.
fn hit_gradient(v: array<f32, 8>, cell: vec3u, local: vec3f) -> vec3f {
  let f = clamp(local, vec3f(0.0), vec3f(1.0));
  var g = vec3f(0.0);
  for (var k = 0u; k < 8u; k++) {
    let o = vec3u(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    var gk = vec3f(0.0);
    if (!voxel_gradient(cell + o, &gk)) {
      return cell_gradient(v, f);
    }
    let w = select(1.0 - f, f, o == vec3u(1u));
    g += w.x * w.y * w.z * gk;
  }
  return g;
}

// The hit lit as the mesh: outside colour where the eye sees the low side
// (marching cubes' outside: out of the value >= iso region), the normal the
// gradient per world unit, toward the eye.
fn lit_hit(v: array<f32, 8>, cell: vec3u, local: vec3f, world: vec3f) -> FragOut {
  let to_eye = normalize(frame.eye.xyz - world);
  let g = hit_gradient(v, cell, local) / rays.voxel_size.xyz;
  var n = -g;
  let gl = length(n);
  var base = rays.front.rgb;
  if (gl > 1e-30) {
    n = n / gl;
    if (dot(n, to_eye) < 0.0) {
      base = rays.back.rgb;
      n = -n;
    }
  } else {
    n = to_eye;
  }
  let colour = lit(base, n, world, rays.front.a, rays.back.a, rays.extra.x, rays.extra.yzw);
  let clip = frame.view_proj * vec4f(world, 1.0);
  return FragOut(vec4f(colour, 1.0), clip.z / clip.w);
}
