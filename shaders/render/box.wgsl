// The volume's bounding box as 12 lines; vertices come from the index.
struct Box {
  min_corner: vec4f,
  max_corner: vec4f,
  color: vec4f,
};
@group(1) @binding(0) var<uniform> box: Box;

// Corner pairs of the 12 edges, corners numbered by bits (x=1, y=2, z=4).
const EDGES = array<u32, 24>(0u,1u, 2u,3u, 4u,5u, 6u,7u, 0u,2u, 1u,3u, 4u,6u, 5u,7u, 0u,4u, 1u,5u, 2u,6u, 3u,7u);

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4f {
  let c = EDGES[vi];
  let p = select(box.min_corner.xyz, box.max_corner.xyz, vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u));
  return frame.view_proj * vec4f(p, 1.0);
}

@fragment
fn fs() -> @location(0) vec4f {
  return box.color;
}
