// The isosurface: a soup of compressed vertices (shaders/isosurface/
// vertex_format.wgsl), shaded with smooth normals from the volume gradient.
//
// Normals: computed once per surface by the pipeline's vertex pass
// (block_emit.wgsl: the central-difference gradient at both ends of the
// vertex's grid edge, interpolated at the vertex -- the gradient VTK's
// ComputeNormals gives) and stored per vertex, octahedral-encoded, in a
// buffer parallel to the vertices: the vertex shader only decodes it.
//
// World space: voxel (i, j, k) sits at ((i, j, k) + origin) * voxel_size (1 on the main
// page; a microscope stack's spacing on the neuron page, where the surface
// shares the space of the volume rendering and the traces).
struct Surface {
  flags: vec4u,        // w: 1 = gradient normals, 0 = flat (xyz unused)
  dims: vec4i,         // voxels per axis
  front: vec4f,        // front (outside) colour; a: ambient
  back: vec4f,         // back (inside) colour;  a: specular strength
  extra: vec4f,        // x: rim strength, y: depth cue, z: near, w: far (eye distance)
  voxel_size: vec4f,   // xyz: world size of a voxel
  origin: vec4f,       // xyz: where voxel (0, 0, 0) sits, in voxels (a store level's OME translation)
  tint: vec4f,         // rgb: multiplies the base colours (a store refined by the view: the level tint; 1 otherwise); a: opacity
  clip_count: vec4u,   // x: planes in use (src/core/clip.ts: a box's six, then the free plane)
  clip: array<vec4f, 7>, // world space: a fragment at w is kept where dot(xyz, w) + w_ >= 0 for every plane
};
@group(1) @binding(0) var<uniform> surface: Surface;

// Depth peeling (fs_peel; src/render/depth-peel.ts): the depth of the layer
// peeled before this one (fragments at or in front of it were drawn already)
// and the opaque scene's depth (fragments behind it are hidden).
@group(2) @binding(0) var peeled_depth: texture_depth_2d;
@group(2) @binding(1) var opaque_depth: texture_depth_2d;

struct VsOut {
  // Invariant: the depth-only entry point (vs_depth) must put every vertex at
  // exactly the same depth, so the volume renderer stops where the surface is drawn.
  @builtin(position) @invariant clip: vec4f,
  @location(0) world: vec3f,
  // Toward decreasing values (out of the value >= iso region); zero when unknown.
  @location(1) normal: vec3f,
};

// The surface's volume in blocks of 4^3: how its vertices number their blocks (vertex_format.wgsl).
fn block_grid() -> vec3u {
  return (vec3u(surface.dims.xyz) + vec3u(3u)) / 4u;
}

fn world_of(p: vec3f) -> vec3f {
  return (p + surface.origin.xyz) * surface.voxel_size.xyz;
}

@vertex
fn vs(@location(0) v: vec2u, @location(1) packed_normal: u32) -> VsOut {
  let p = decode_vertex_position(v.x, v.y, block_grid());
  var out: VsOut;
  out.world = world_of(p);
  out.clip = frame.view_proj * vec4f(out.world, 1.0);
  out.normal = vec3f(0.0);
  if (surface.flags.w != 0u) {
    // The gradient in index space, per world unit: d/dx_world = d/dx_index / voxel size.
    out.normal = decode_vertex_normal(packed_normal) / surface.voxel_size.xyz;
  }
  return out;
}

struct DepthOut {
  @builtin(position) @invariant clip: vec4f,
};

// Depth only (opaque-layer pre-pass of the neuron page): positions only.
@vertex
fn vs_depth(@location(0) v: vec2u) -> DepthOut {
  let p = decode_vertex_position(v.x, v.y, block_grid());
  return DepthOut(frame.view_proj * vec4f(world_of(p), 1.0));
}

// Cut open: outside any clip plane, nothing is drawn.
fn clipped(world: vec3f) -> bool {
  for (var i = 0u; i < min(surface.clip_count.x, 7u); i++) {
    let p = surface.clip[i];
    if (dot(p.xyz, world) + p.w < 0.0) {
      return true;
    }
  }
  return false;
}

@fragment
fn fs(in: VsOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4f {
  let colour = shade(in, front_facing); // first: derivatives need uniform control flow
  if (clipped(in.world)) {
    discard;
  }
  return vec4f(colour, 1.0);
}

// One layer of a see-through surface: the nearest fragment behind the layer
// peeled before (depth test 'less' into a cleared depth) and in front of the
// opaque scene, premultiplied by the surface's opacity. Depths are compared
// as the float32 the depth targets store, so a fragment peeled once is never
// peeled again.
@fragment
fn fs_peel(in: VsOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4f {
  let colour = shade(in, front_facing); // first: derivatives need uniform control flow
  let pixel = vec2i(in.clip.xy);
  if (clipped(in.world) || in.clip.z <= textureLoad(peeled_depth, pixel, 0) || in.clip.z >= textureLoad(opaque_depth, pixel, 0)) {
    discard;
  }
  let a = surface.tint.a;
  return vec4f(colour * a, a);
}

// The lit colour (sRGB-encoded, as the canvas shows it).
fn shade(in: VsOut, front_facing: bool) -> vec3f {
  let to_eye = normalize(frame.eye.xyz - in.world);
  // Marching cubes winds triangles so that their right-hand normal points
  // out of the value >= iso region (VTK's convention): a front-facing
  // triangle shows the outside, a back-facing one the inside.
  var base = surface.front.rgb;
  if (!front_facing) {
    base = surface.back.rgb;
  }
  base *= surface.tint.rgb;
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
  return lit(base, n, in.world, surface.front.a, surface.back.a, surface.extra.x, surface.extra.yzw);
}
