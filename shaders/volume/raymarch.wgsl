// GPU ray-marched volume rendering of a 3D texture through a transfer
// function. The proxy geometry is the volume's box drawn with its back faces,
// so rays also start correctly when the camera is inside the box. Rays stop
// at opaque geometry (neuron traces, the isosurface) by reading the
// depth those layers wrote in a pre-pass. Output is premultiplied alpha.
// Needs frame.wgsl (group 0).

struct Volume {
  inv_view_proj: mat4x4f,
  box_min: vec4f,   // world-space corner of the box (voxel edges, not centres)
  box_size: vec4f,  // world-space size of the box
  step: f32,        // world-space distance between samples
  opacity: f32,     // opacity of a fully opaque TF entry over one reference step
  window_lo: f32,   // normalised data value mapped to the start of the TF
  window_hi: f32,   // ... and to its end
  mode: u32,        // 0 emission-absorption compositing, 1 maximum intensity projection
  max_steps: u32,
  has_depth: u32,   // 1 when opaque_depth holds the pre-pass depth
  ref_step: f32,    // step the opacity is defined for (one voxel)
};

@group(1) @binding(0) var<uniform> vol: Volume;
@group(1) @binding(1) var volume_tex: texture_3d<f32>;
@group(1) @binding(2) var linear_clamp: sampler;
@group(1) @binding(3) var tf_tex: texture_2d<f32>;
@group(1) @binding(4) var opaque_depth: texture_depth_2d;

struct VsOut {
  @builtin(position) position: vec4f,
  @location(0) world: vec3f,
};

// 12 triangles of the unit cube, corners numbered by bits (x=1, y=2, z=4),
// wound counter-clockwise seen from outside.
const CUBE = array<u32, 36>(
  0u, 2u, 1u, 1u, 2u, 3u,  // z = 0
  4u, 5u, 6u, 5u, 7u, 6u,  // z = 1
  0u, 1u, 4u, 1u, 5u, 4u,  // y = 0
  2u, 6u, 3u, 3u, 6u, 7u,  // y = 1
  0u, 4u, 2u, 2u, 4u, 6u,  // x = 0
  1u, 3u, 5u, 3u, 7u, 5u,  // x = 1
);

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> VsOut {
  let c = CUBE[vi];
  let unit = vec3f(f32(c & 1u), f32((c >> 1u) & 1u), f32((c >> 2u) & 1u));
  let world = vol.box_min.xyz + unit * vol.box_size.xyz;
  var out: VsOut;
  out.position = frame.view_proj * vec4f(world, 1.0);
  out.world = world;
  return out;
}

// Interleaved gradient noise: a per-pixel start offset that turns
// wood-grain banding into fine noise.
fn ign(p: vec2f) -> f32 {
  return fract(52.9829189 * fract(dot(p, vec2f(0.06711056, 0.00583715))));
}

fn sample_value(p: vec3f) -> f32 {
  let tc = (p - vol.box_min.xyz) / vol.box_size.xyz;
  let v = textureSampleLevel(volume_tex, linear_clamp, tc, 0.0).r;
  return (v - vol.window_lo) / max(vol.window_hi - vol.window_lo, 1e-6);
}

fn transfer(s: f32) -> vec4f {
  return textureSampleLevel(tf_tex, linear_clamp, vec2f(clamp(s, 0.0, 1.0), 0.5), 0.0);
}

@fragment
fn fs(in: VsOut) -> @location(0) vec4f {
  let eye = frame.eye.xyz;
  let dir = normalize(in.world - eye);
  // Slab test against the box.
  let inv = 1.0 / dir;
  let ta = (vol.box_min.xyz - eye) * inv;
  let tb = (vol.box_min.xyz + vol.box_size.xyz - eye) * inv;
  let tmin = min(ta, tb);
  let tmax = max(ta, tb);
  var t0 = max(max(max(tmin.x, tmin.y), tmin.z), 0.0);
  var t1 = min(min(tmax.x, tmax.y), tmax.z);
  if (vol.has_depth == 1u) {
    let d = textureLoad(opaque_depth, vec2i(in.position.xy), 0);
    if (d < 1.0) {
      // The opaque surface's world position, and its distance along the ray.
      let ndc = vec2f(in.position.x * frame.viewport.z * 2.0 - 1.0, 1.0 - in.position.y * frame.viewport.w * 2.0);
      let h = vol.inv_view_proj * vec4f(ndc, d, 1.0);
      t1 = min(t1, dot(h.xyz / h.w - eye, dir));
    }
  }
  if (t1 <= t0) { discard; }

  var t = t0 + ign(in.position.xy) * vol.step;
  var acc = vec4f(0.0);
  var peak = 0.0;
  // Opacity correction: a TF alpha is defined per reference step.
  let exponent = vol.step / vol.ref_step;
  for (var i = 0u; i < vol.max_steps; i++) {
    if (t >= t1) { break; }
    let s = sample_value(eye + dir * t);
    if (vol.mode == 1u) {
      peak = max(peak, s);
    } else if (s > 0.0) {
      let c = transfer(s);
      let a = 1.0 - pow(1.0 - clamp(c.a * vol.opacity, 0.0, 0.9999), exponent);
      acc += vec4f(c.rgb * a, a) * (1.0 - acc.a);
      if (acc.a > 0.985) { break; }
    }
    t += vol.step;
  }
  if (vol.mode == 1u) {
    let c = transfer(peak);
    let a = clamp(peak, 0.0, 1.0) * clamp(vol.opacity * 4.0, 0.0, 1.0);
    return vec4f(c.rgb * a, a);
  }
  return acc;
}
