// The isosurface: a soup of compressed vertices (shaders/isosurface/
// vertex_format.wgsl), shaded with smooth normals from the volume gradient.
//
// Normals: a marching-cubes vertex lies on a grid edge between two voxels.
// We take the central-difference gradient at both ends, read from the
// decoded-block cache (every block the drawn surface touches is cached), and
// interpolate it at the vertex's position on the edge -- the same gradient
// VTK's ComputeNormals gives, without a normal buffer. A neighbour voxel in a
// block that is not cached (or outside the volume) gives a one-sided
// difference instead.
//
// World space: voxel (i, j, k) sits at (i, j, k) * voxel_size (1 on the main
// page; a microscope stack's spacing on the neuron page, where the surface
// shares the space of the volume rendering and the traces).
struct Surface {
  block_grid: vec4u,   // blocks per axis; w: 1 = gradient normals, 0 = flat
  dims: vec4i,         // voxels per axis
  front: vec4f,        // front (outside) colour; a: ambient
  back: vec4f,         // back (inside) colour;  a: specular strength
  extra: vec4f,        // x: rim strength, y: depth cue, z: near, w: far (eye distance)
  voxel_size: vec4f,   // xyz: world size of a voxel
};
@group(1) @binding(0) var<uniform> surface: Surface;
@group(1) @binding(1) var<storage, read> slot_data: array<f32>;
@group(1) @binding(2) var<storage, read> block_to_slot: array<u32>;

const NOT_CACHED: u32 = 0xffffffffu;

struct VsOut {
  // Invariant: the depth-only entry point (vs_depth) must put every vertex at
  // exactly the same depth, so the volume renderer stops where the surface is drawn.
  @builtin(position) @invariant clip: vec4f,
  @location(0) world: vec3f,
  // Toward decreasing values (out of the value >= iso region); zero when unknown.
  @location(1) normal: vec3f,
};

// The voxel at grid point g: (value, 1) when it is cached, (0, 0) otherwise.
fn voxel(g: vec3i) -> vec2f {
  if (any(g < vec3i(0)) || any(g >= surface.dims.xyz)) {
    return vec2f(0.0);
  }
  let b = vec3u(g) >> vec3u(2u);
  let grid = surface.block_grid.xyz;
  let slot = block_to_slot[b.x + grid.x * (b.y + grid.y * b.z)];
  if (slot == NOT_CACHED) {
    return vec2f(0.0);
  }
  let l = vec3u(g) & vec3u(3u);
  return vec2f(slot_data[slot * 64u + l.x + 4u * l.y + 16u * l.z], 1.0);
}

// One component of the gradient at g along `axis` (central, else one-sided).
fn partial(g: vec3i, center: vec2f, axis: vec3i) -> f32 {
  let p = voxel(g + axis);
  let m = voxel(g - axis);
  if (p.y > 0.0 && m.y > 0.0) {
    return 0.5 * (p.x - m.x);
  }
  if (center.y == 0.0) {
    return 0.0;
  }
  if (p.y > 0.0) {
    return p.x - center.x;
  }
  if (m.y > 0.0) {
    return center.x - m.x;
  }
  return 0.0;
}

fn gradient(g: vec3i) -> vec3f {
  let c = voxel(g);
  return vec3f(partial(g, c, vec3i(1, 0, 0)), partial(g, c, vec3i(0, 1, 0)), partial(g, c, vec3i(0, 0, 1)));
}

// Gradient at a vertex on a grid edge: the edge runs along the axis whose
// coordinate is farthest from a whole number; the other two are whole.
fn edge_gradient(p: vec3f) -> vec3f {
  let r = round(p);
  let d = abs(p - r);
  var axis = vec3i(1, 0, 0);
  var t = p.x - floor(p.x);
  if (d.y > d.x && d.y >= d.z) {
    axis = vec3i(0, 1, 0);
    t = p.y - floor(p.y);
  } else if (d.z > d.x && d.z > d.y) {
    axis = vec3i(0, 0, 1);
    t = p.z - floor(p.z);
  }
  let g0 = select(vec3i(r), vec3i(floor(p)), axis != vec3i(0));
  return mix(gradient(g0), gradient(g0 + axis), t);
}

fn world_of(p: vec3f) -> vec3f {
  return p * surface.voxel_size.xyz;
}

@vertex
fn vs(@location(0) v: vec2u) -> VsOut {
  let p = decode_vertex_position(v.x, v.y, surface.block_grid.xyz);
  var out: VsOut;
  out.world = world_of(p);
  out.clip = frame.view_proj * vec4f(out.world, 1.0);
  out.normal = vec3f(0.0);
  if (surface.block_grid.w != 0u) {
    // The gradient in index space, per world unit: d/dx_world = d/dx_index / voxel size.
    out.normal = -edge_gradient(p) / surface.voxel_size.xyz;
  }
  return out;
}

struct DepthOut {
  @builtin(position) @invariant clip: vec4f,
};

// Depth only (opaque-layer pre-pass of the neuron page): no normals, so no cache reads.
@vertex
fn vs_depth(@location(0) v: vec2u) -> DepthOut {
  let p = decode_vertex_position(v.x, v.y, surface.block_grid.xyz);
  return DepthOut(frame.view_proj * vec4f(world_of(p), 1.0));
}

fn to_srgb(c: vec3f) -> vec3f {
  return pow(clamp(c, vec3f(0.0), vec3f(1.0)), vec3f(1.0 / 2.2));
}

@fragment
fn fs(in: VsOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4f {
  let to_eye = normalize(frame.eye.xyz - in.world);
  // Marching cubes winds triangles so that their right-hand normal points
  // out of the value >= iso region (VTK's convention): a front-facing
  // triangle shows the outside, a back-facing one the inside.
  var base = surface.front.rgb;
  if (!front_facing) {
    base = surface.back.rgb;
  }
  // The triangle's own normal (derivatives must be taken in uniform control flow).
  let face = cross(dpdx(in.world), dpdy(in.world));
  var n: vec3f;
  let g = length(in.normal);
  if (g > 1e-12) {
    n = in.normal / g;
    if (!front_facing) {
      n = -n;
    }
    // Near silhouettes the interpolated normal may lean away from the eye:
    // mirror it into the visible half-space.
    let d = dot(n, to_eye);
    if (d < 0.0) {
      n = normalize(n - 2.0 * d * to_eye);
    }
  } else {
    // Flat shading (or no usable gradient): the triangle's own normal, toward the eye.
    n = normalize(face);
    if (dot(n, to_eye) < 0.0) {
      n = -n;
    }
  }
  // Camera axes in world space (rows of the view rotation).
  let right = vec3f(frame.view[0].x, frame.view[1].x, frame.view[2].x);
  let up = vec3f(frame.view[0].y, frame.view[1].y, frame.view[2].y);
  // Headlight, a little above and left of the eye, and a dim fill from below right.
  let key = normalize(to_eye + 0.45 * up - 0.3 * right);
  let fill = normalize(to_eye - 0.6 * up + 0.5 * right);
  let diffuse = max(dot(n, key), 0.0) * 0.78 + max(dot(n, fill), 0.0) * 0.18;
  let h = normalize(key + to_eye);
  let specular = pow(max(dot(n, h), 0.0), 60.0) * surface.back.a;
  let rim = pow(1.0 - max(dot(n, to_eye), 0.0), 3.0) * surface.extra.x;
  let ambient = surface.front.a;
  // base colour in linear light
  let albedo = pow(base, vec3f(2.2));
  var c = albedo * (ambient + diffuse) + vec3f(specular + rim * 0.6);
  // Depth cue: far parts fade a little toward the background.
  let dist = length(frame.eye.xyz - in.world);
  let far_t = clamp((dist - surface.extra.z) / max(surface.extra.w - surface.extra.z, 1e-6), 0.0, 1.0);
  c = mix(c, c * 0.55, far_t * surface.extra.y);
  return vec4f(to_srgb(c), 1.0);
}
