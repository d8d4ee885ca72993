// Neuron traces (SWC) in the volume's space: each segment (sample to parent)
// as a line, or as a tube: a screen-aligned quad as wide as the segment's
// radii (never thinner than min_px) shaded like a cylinder, with a sphere
// impostor at every sample to round the joints. The same shader writes depth
// only for the pre-pass that lets the volume's rays stop at the traces.
// Needs frame.wgsl (group 0).

struct Traces {
  // Pixels per world unit at view distance 1 (the projection's focal length in pixels).
  focal_px: f32,
  min_px: f32,
  radius_scale: f32,
  _pad: f32,
};

struct Segment {
  a: vec4f,      // xyz, radius
  b: vec4f,      // xyz, radius
  color: vec4f,  // rgb, 1
};

@group(1) @binding(0) var<uniform> traces: Traces;
@group(1) @binding(1) var<storage, read> segments: array<Segment>;

struct VsOut {
  @builtin(position) position: vec4f,
  @location(0) color: vec3f,
  // x: across the tube / disc (-1..1), y: along the disc (-1..1)
  @location(1) uv: vec2f,
};

@vertex
fn vs_line(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VsOut {
  let s = segments[ii];
  var out: VsOut;
  let p = select(s.b.xyz, s.a.xyz, vi == 0u);
  out.position = frame.view_proj * vec4f(p, 1.0);
  out.color = s.color.rgb;
  out.uv = vec2f(0.0);
  return out;
}

const QUAD = array<vec2f, 6>(vec2f(-1, 0), vec2f(1, 0), vec2f(1, 1), vec2f(-1, 0), vec2f(1, 1), vec2f(-1, 1));
const DISC = array<vec2f, 6>(vec2f(-1, -1), vec2f(1, -1), vec2f(1, 1), vec2f(-1, -1), vec2f(1, 1), vec2f(-1, 1));

fn radius_px(r: f32, w: f32) -> f32 {
  return max(r * traces.radius_scale * traces.focal_px / max(w, 1e-6), traces.min_px * 0.5);
}

@vertex
fn vs_tube(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VsOut {
  let s = segments[ii];
  let q = QUAD[vi];
  let ca = frame.view_proj * vec4f(s.a.xyz, 1.0);
  let cb = frame.view_proj * vec4f(s.b.xyz, 1.0);
  let half_vp = frame.viewport.xy * 0.5;
  // Screen-space direction of the segment (pixels); any direction when it points at the eye.
  let sa = ca.xy / max(ca.w, 1e-6) * half_vp;
  let sb = cb.xy / max(cb.w, 1e-6) * half_vp;
  var d = sb - sa;
  if (dot(d, d) < 1e-8) { d = vec2f(1.0, 0.0); }
  d = normalize(d);
  let perp = vec2f(-d.y, d.x);
  let c = select(ca, cb, q.y > 0.5);
  let r = select(s.a.w, s.b.w, q.y > 0.5);
  let offset = perp * q.x * radius_px(r, c.w);
  var out: VsOut;
  out.position = vec4f(c.xy + offset / half_vp * c.w, c.zw);
  out.color = s.color.rgb;
  out.uv = vec2f(q.x, 0.0);
  return out;
}

// A disc at the child end of every segment fills the joints of the tubes.
@vertex
fn vs_joint(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VsOut {
  let s = segments[ii];
  let q = DISC[vi];
  let c = frame.view_proj * vec4f(s.a.xyz, 1.0);
  let half_vp = frame.viewport.xy * 0.5;
  let offset = q * radius_px(s.a.w, c.w);
  var out: VsOut;
  out.position = vec4f(c.xy + offset / half_vp * c.w, c.zw);
  out.color = s.color.rgb;
  out.uv = q;
  return out;
}

@fragment
fn fs_line(in: VsOut) -> @location(0) vec4f {
  return vec4f(in.color, 1.0);
}

@fragment
fn fs_tube(in: VsOut) -> @location(0) vec4f {
  // Lambert from a headlight on a cylinder: the normal turns across the tube.
  let n = sqrt(max(1.0 - in.uv.x * in.uv.x, 0.0));
  return vec4f(in.color * (0.3 + 0.7 * n) + vec3f(0.25 * pow(n, 24.0)), 1.0);
}

@fragment
fn fs_joint(in: VsOut) -> @location(0) vec4f {
  let r2 = dot(in.uv, in.uv);
  if (r2 > 1.0) { discard; }
  let n = sqrt(1.0 - r2);
  return vec4f(in.color * (0.3 + 0.7 * n) + vec3f(0.25 * pow(n, 24.0)), 1.0);
}

// Depth pre-pass: same geometry, no colour.
@fragment
fn fs_joint_depth(in: VsOut) {
  if (dot(in.uv, in.uv) > 1.0) { discard; }
}
