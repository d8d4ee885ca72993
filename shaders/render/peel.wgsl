// Depth peeling (order-independent transparency), the two full-screen
// composites: each peeled layer goes UNDER what is accumulated in front of
// it (front to back), then the accumulation goes OVER the opaque image.
// Colours are premultiplied by alpha; blending is fixed-function:
//   under: accum += (1 - accum.a) * layer   (src one-minus-dst-alpha, dst one)
//   over:  target = accum + (1 - accum.a) * target   (src one, dst one-minus-src-alpha)
@group(0) @binding(0) var layer_colour: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
  // one triangle over the whole target
  let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
  return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_composite(@builtin(position) p: vec4f) -> @location(0) vec4f {
  return textureLoad(layer_colour, vec2i(p.xy), 0);
}
