// Per-frame uniforms shared by every render pass (bind group 0).
struct Frame {
  view_proj: mat4x4f,
  view: mat4x4f,
  eye: vec4f,       // world-space camera position
  light_dir: vec4f, // world-space direction toward the light (headlight)
  viewport: vec4f,  // width, height in pixels, 1/width, 1/height
};
@group(0) @binding(0) var<uniform> frame: Frame;
