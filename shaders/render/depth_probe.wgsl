// Reads one texel of a depth texture into a buffer (a pick): depth/stencil
// textures cannot be copied in part, so a one-thread kernel loads it.
struct Probe {
  x: u32,
  y: u32,
  slot: u32,
  pad: u32,
};
@group(0) @binding(0) var depth: texture_depth_2d;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;
@group(0) @binding(2) var<uniform> probe: Probe;

@compute @workgroup_size(1)
fn read_depth() {
  out[probe.slot] = textureLoad(depth, vec2u(probe.x, probe.y), 0);
}
