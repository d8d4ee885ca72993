// Caps: where a clip cuts the volume open, its polygon on the clip plane is
// coloured by the volume's values there (a slice: the trilinear value of the
// decoded voxels at each fragment) wherever the value is at least the
// threshold (inside the outermost surface), and left open elsewhere. The
// voxels come from the blocks near the caps, decoded once per clip
// (src/render/cap-layer.ts): `cap_blocks` lists their ids in increasing
// order, `cap_values` holds 64 values per listed block (x + 4y + 16z),
// `cap_owned` whether this piece draws the cells of a listed block (a store's
// level draws only its own regions; cells of blocks it does not own are
// another level's).
struct Cap {
  dims: vec4i,        // voxels per axis; w: listed blocks
  grid: vec4u,        // blocks per axis
  voxel_size: vec4f,  // xyz: world size of a voxel; w: the threshold
  origin: vec4f,      // xyz: where voxel (0, 0, 0) sits, in voxels
  range: vec4f,       // x, y: the values the colour map spans
};
@group(1) @binding(0) var<uniform> cap: Cap;
@group(1) @binding(1) var<storage, read> cap_blocks: array<u32>;
@group(1) @binding(2) var<storage, read> cap_values: array<f32>;
@group(1) @binding(3) var<storage, read> cap_owned: array<u32>;

struct VsOut {
  @builtin(position) clip: vec4f,
  @location(0) voxel: vec3f,
};

@vertex
fn vs(@location(0) p: vec3f) -> VsOut {
  var out: VsOut;
  out.voxel = p;
  out.clip = frame.view_proj * vec4f((p + cap.origin.xyz) * cap.voxel_size.xyz, 1.0);
  return out;
}

// The list index of block `id`, or -1 (binary search over the increasing ids).
fn listed(id: u32) -> i32 {
  var lo = 0i;
  var hi = cap.dims.w - 1;
  while (lo <= hi) {
    let mid = (lo + hi) / 2;
    let b = cap_blocks[mid];
    if (b == id) {
      return mid;
    }
    if (b < id) {
      lo = mid + 1;
    } else {
      hi = mid - 1;
    }
  }
  return -1;
}

// A voxel's decoded value; NaN-like (-3e38) where its block is not listed.
fn voxel_value(c: vec3i) -> f32 {
  let v = clamp(c, vec3i(0), cap.dims.xyz - vec3i(1));
  let b = vec3u(v) / 4u;
  let k = listed(b.x + cap.grid.x * (b.y + cap.grid.y * b.z));
  if (k < 0) {
    return -3e38;
  }
  let r = vec3u(v) % 4u;
  return cap_values[u32(k) * 64u + r.x + 4u * r.y + 16u * r.z];
}

// Dark blue, teal, green, yellow (sRGB), linear between the stops.
fn colour_map(t: f32) -> vec3f {
  let stops = array<vec3f, 5>(
    vec3f(0.15, 0.1, 0.4),
    vec3f(0.2, 0.35, 0.6),
    vec3f(0.15, 0.6, 0.55),
    vec3f(0.5, 0.8, 0.3),
    vec3f(0.98, 0.9, 0.15),
  );
  let x = clamp(t, 0.0, 1.0) * 4.0;
  let i = min(u32(floor(x)), 3u);
  return mix(stops[i], stops[i + 1u], x - f32(i));
}

@fragment
fn fs(in: VsOut) -> @location(0) vec4f {
  let lower = vec3i(floor(in.voxel));
  let f = in.voxel - vec3f(lower);
  let own = vec3u(clamp(lower, vec3i(0), cap.dims.xyz - vec3i(1))) / 4u;
  let k_own = listed(own.x + cap.grid.x * (own.y + cap.grid.y * own.z));
  if (k_own < 0 || cap_owned[u32(k_own)] == 0u) {
    discard;
  }
  var value = 0.0;
  for (var k = 0u; k < 8u; k++) {
    let o = vec3u(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    let w = select(1.0 - f, f, vec3<bool>(o == vec3u(1u)));
    value += w.x * w.y * w.z * voxel_value(lower + vec3i(o));
  }
  if (!(value >= cap.voxel_size.w)) {
    discard;
  }
  let t = (value - cap.range.x) / max(cap.range.y - cap.range.x, 1e-30);
  return vec4f(colour_map(t), 1.0);
}
