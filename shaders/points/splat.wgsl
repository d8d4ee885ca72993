// Point clouds as screen-space splats: one instance per point, 6 vertices
// (two triangles) per instance, billboarded in clip space so every point
// covers `size` pixels whatever its depth. Round splats discard the corners
// and darken toward the rim, which reads as depth in dense clouds.
// Needs frame.wgsl (group 0).

struct Style {
  // 0 RGB, 1 intensity, 2 elevation, 3 classification
  color_mode: u32,
  // 0 square, 1 round
  shape: u32,
  size_px: f32,
  // Scales the stored 8-bit RGB (1/255), kept as a uniform for files with dim colours.
  rgb_scale: f32,
  // Intensity window (after the 2%..98% stretch) and elevation range, in data units.
  intensity_lo: f32,
  intensity_hi: f32,
  z_lo: f32,
  z_hi: f32,
  // Bit per class (0..31) that is hidden.
  hidden_classes: u32,
  _pad0: u32,
  _pad1: u32,
  _pad2: u32,
};

@group(1) @binding(0) var<uniform> style: Style;
// x, y, z per point (relative to the cloud's centre).
@group(1) @binding(1) var<storage, read> positions: array<f32>;
// Per point: word 0 = r | g << 8 | b << 16 | class << 24 (8 bits each), word 1 = intensity (16 bits).
@group(1) @binding(2) var<storage, read> attributes: array<vec2u>;

struct VsOut {
  @builtin(position) position: vec4f,
  @location(0) color: vec3f,
  @location(1) corner: vec2f,
};

const CORNERS = array<vec2f, 6>(vec2f(-1, -1), vec2f(1, -1), vec2f(1, 1), vec2f(-1, -1), vec2f(1, 1), vec2f(-1, 1));

// ASPRS LAS classes 0..18, then a stable hue per code.
fn class_color(c: u32) -> vec3f {
  switch c {
    case 0u, 1u: { return vec3f(0.62, 0.62, 0.62); }  // never classified, unclassified
    case 2u: { return vec3f(0.68, 0.52, 0.32); }      // ground
    case 3u: { return vec3f(0.55, 0.80, 0.35); }      // low vegetation
    case 4u: { return vec3f(0.28, 0.68, 0.25); }      // medium vegetation
    case 5u: { return vec3f(0.10, 0.48, 0.16); }      // high vegetation
    case 6u: { return vec3f(0.90, 0.30, 0.25); }      // building
    case 7u: { return vec3f(1.00, 0.10, 0.80); }      // low point (noise)
    case 8u: { return vec3f(0.95, 0.85, 0.20); }      // model key / reserved
    case 9u: { return vec3f(0.20, 0.50, 0.95); }      // water
    case 10u: { return vec3f(0.75, 0.45, 0.85); }     // rail
    case 11u: { return vec3f(0.45, 0.45, 0.50); }     // road surface
    case 12u: { return vec3f(0.85, 0.85, 0.55); }     // overlap / reserved
    case 13u, 14u: { return vec3f(0.95, 0.65, 0.20); } // wire guard / conductor
    case 15u: { return vec3f(0.90, 0.90, 0.90); }     // transmission tower
    case 16u: { return vec3f(0.60, 0.90, 0.90); }     // wire connector
    case 17u: { return vec3f(0.55, 0.35, 0.25); }     // bridge deck
    case 18u: { return vec3f(1.00, 0.00, 0.00); }     // high noise
    default: {
      let h = fract(f32(c) * 0.618034);
      return 0.35 + 0.6 * clamp(abs(fract(h + vec3f(0.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0) - 1.0, vec3f(0.0), vec3f(1.0));
    }
  }
}

// A perceptually ordered ramp (close to matplotlib's viridis) for scalars in [0, 1].
fn viridis(t: f32) -> vec3f {
  let x = clamp(t, 0.0, 1.0);
  let c0 = vec3f(0.2777, 0.0054, 0.3341);
  let c1 = vec3f(0.1051, 1.4046, 1.3846);
  let c2 = vec3f(-0.3309, 0.2148, 0.0951);
  let c3 = vec3f(-4.6342, -5.7991, -19.3324);
  let c4 = vec3f(6.2283, 14.1799, 56.6906);
  let c5 = vec3f(4.7764, -13.7451, -65.3530);
  let c6 = vec3f(-5.4355, 4.6459, 26.3124);
  return c0 + x * (c1 + x * (c2 + x * (c3 + x * (c4 + x * (c5 + x * c6)))));
}

// Terrain-like ramp for elevation: blue-green lowlands to brown and white peaks.
fn terrain(t: f32) -> vec3f {
  let x = clamp(t, 0.0, 1.0);
  let a = vec3f(0.16, 0.35, 0.62);
  let b = vec3f(0.30, 0.62, 0.36);
  let c = vec3f(0.86, 0.80, 0.45);
  let d = vec3f(0.58, 0.38, 0.24);
  let e = vec3f(0.97, 0.97, 0.97);
  if (x < 0.25) { return mix(a, b, x / 0.25); }
  if (x < 0.5) { return mix(b, c, (x - 0.25) / 0.25); }
  if (x < 0.75) { return mix(c, d, (x - 0.5) / 0.25); }
  return mix(d, e, (x - 0.75) / 0.25);
}

@vertex
fn vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VsOut {
  var out: VsOut;
  let a = attributes[ii];
  let cls = a.x >> 24u;
  if (cls < 32u && ((style.hidden_classes >> cls) & 1u) == 1u) {
    // Hidden class: a degenerate triangle outside the clip volume.
    out.position = vec4f(2.0, 2.0, 2.0, 1.0);
    return out;
  }
  let p = vec3f(positions[3u * ii], positions[3u * ii + 1u], positions[3u * ii + 2u]);
  let clip = frame.view_proj * vec4f(p, 1.0);
  let corner = CORNERS[vi];
  // Pixels to clip units: 2 / viewport, times w to undo the perspective divide.
  out.position = vec4f(clip.xy + corner * style.size_px * frame.viewport.zw * clip.w, clip.zw);
  out.corner = corner;
  var color: vec3f;
  switch style.color_mode {
    case 0u: {
      color = vec3f(f32(a.x & 0xffu), f32((a.x >> 8u) & 0xffu), f32((a.x >> 16u) & 0xffu)) * style.rgb_scale;
    }
    case 1u: {
      let i = f32(a.y & 0xffffu);
      let t = (i - style.intensity_lo) / max(style.intensity_hi - style.intensity_lo, 1e-6);
      color = vec3f(pow(clamp(t, 0.0, 1.0), 0.8));
    }
    case 2u: {
      color = terrain((p.z - style.z_lo) / max(style.z_hi - style.z_lo, 1e-6));
    }
    default: {
      color = class_color(cls);
    }
  }
  out.color = color;
  return out;
}

@fragment
fn fs(in: VsOut) -> @location(0) vec4f {
  var shade = 1.0;
  if (style.shape == 1u) {
    let r2 = dot(in.corner, in.corner);
    if (r2 > 1.0) { discard; }
    // A hint of a sphere: darker toward the rim.
    shade = 1.0 - 0.35 * r2 * r2;
  }
  return vec4f(in.color * shade, 1.0);
}
