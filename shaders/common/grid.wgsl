// Linear index of a workgroup in a 2D dispatch grid (x fastest). Dispatches
// over 65535 workgroups use y > 1; kernels must ignore indices past the count.
fn linear_workgroup_index(workgroup_id: vec3u, num_workgroups: vec3u) -> u32 {
  return workgroup_id.x + workgroup_id.y * num_workgroups.x;
}
