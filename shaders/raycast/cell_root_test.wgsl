// Test harness for cell_root.wgsl (tests/unit/raycast/cell-root.test.ts): one
// invocation per case. A case is 17 floats: the 8 corners (x fastest), iso,
// origin (3), dir (3), t0, t1. Out: (t or CELL_ROOT_NONE, cell_gradient at the
// origin) per case; the case count is the output's length.
@group(0) @binding(0) var<storage, read> cases: array<f32>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4f>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
  let i = gid.x;
  if (i >= arrayLength(&results)) {
    return;
  }
  let b = 17u * i;
  var v: array<f32, 8>;
  for (var j = 0u; j < 8u; j++) {
    v[j] = cases[b + j];
  }
  let iso = cases[b + 8u];
  let origin = vec3f(cases[b + 9u], cases[b + 10u], cases[b + 11u]);
  let dir = vec3f(cases[b + 12u], cases[b + 13u], cases[b + 14u]);
  let t = cell_first_crossing(v, iso, origin, dir, cases[b + 15u], cases[b + 16u]);
  results[i] = vec4f(t, cell_gradient(v, origin));
}
