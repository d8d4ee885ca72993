// The lighting of a surface point (the mesh, shaders/render/surface.wgsl, and
// the ray-cast surface, raycast.wgsl, alike): a headlight a little above and
// left of the eye and a dim fill from below right, Blinn specular, a rim, and
// a depth cue toward the far side; `base` (sRGB) and the unit normal `n`
// toward the eye given. Needs frame.wgsl.

fn to_srgb(c: vec3f) -> vec3f {
  return pow(clamp(c, vec3f(0.0), vec3f(1.0)), vec3f(1.0 / 2.2));
}

// `cue`: depth-cue strength, near and far eye distances. The lit colour, sRGB-encoded.
fn lit(base: vec3f, n: vec3f, world: vec3f, ambient: f32, specular_strength: f32, rim_strength: f32, cue: vec3f) -> vec3f {
  let to_eye = normalize(frame.eye.xyz - world);
  // Camera axes in world space (rows of the view rotation).
  let right = vec3f(frame.view[0].x, frame.view[1].x, frame.view[2].x);
  let up = vec3f(frame.view[0].y, frame.view[1].y, frame.view[2].y);
  // Headlight, a little above and left of the eye, and a dim fill from below right.
  let key = normalize(to_eye + 0.45 * up - 0.3 * right);
  let fill = normalize(to_eye - 0.6 * up + 0.5 * right);
  let diffuse = max(dot(n, key), 0.0) * 0.78 + max(dot(n, fill), 0.0) * 0.18;
  let h = normalize(key + to_eye);
  let specular = pow(max(dot(n, h), 0.0), 60.0) * specular_strength;
  let rim = pow(1.0 - max(dot(n, to_eye), 0.0), 3.0) * rim_strength;
  // base colour in linear light
  let albedo = pow(base, vec3f(2.2));
  var c = albedo * (ambient + diffuse) + vec3f(specular + rim * 0.6);
  // Depth cue: far parts fade a little toward the background.
  let dist = length(frame.eye.xyz - world);
  let far_t = clamp((dist - cue.y) / max(cue.z - cue.y, 1e-6), 0.0, 1.0);
  c = mix(c, c * 0.55, far_t * cue.x);
  return to_srgb(c);
}
