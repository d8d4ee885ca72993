// The clip's handles over the view: discs (a face of the clip box, the
// plane's centre and rotation knob) and lines (the plane's outline, the
// knob's stick), each sized in pixels so it stays grabbable at any zoom.
// Drawn in a pass of their own after the scene, without depth: always on top.
struct Item {
  a: vec4f,     // world position (a disc's centre, a line's start)
  b: vec4f,     // a line's end
  color: vec4f,
  shape: vec4f, // x: radius or half-width in pixels, y: 0 disc, 1 line
};
@group(1) @binding(0) var<uniform> items: array<Item, 16>;

struct Out {
  @builtin(position) position: vec4f,
  @location(0) local: vec2f, // a disc's corner at (+-1, +-1); (0, 0) on lines
  @location(1) @interpolate(flat) item: u32,
};

// Two triangles of a quad: (side along, side across) per corner.
const CORNERS = array<vec2f, 6>(vec2f(-1.0, -1.0), vec2f(1.0, -1.0), vec2f(1.0, 1.0), vec2f(-1.0, -1.0), vec2f(1.0, 1.0), vec2f(-1.0, 1.0));

fn to_ndc(p: vec4f) -> vec3f {
  let c = frame.view_proj * vec4f(p.xyz, 1.0);
  // behind the eye: pushed out of the clip volume (such handles cannot be grabbed either)
  return select(vec3f(4.0, 4.0, 0.0), vec3f(c.xy / c.w, 1.0), c.w > 0.0);
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Out {
  let item = items[vi / 6u];
  let corner = CORNERS[vi % 6u];
  let px = 2.0 * frame.viewport.zw; // one pixel in NDC
  var out: Out;
  out.item = vi / 6u;
  if (item.shape.y < 0.5) {
    let c = to_ndc(item.a);
    out.position = vec4f(c.xy + corner * item.shape.x * px, 0.0, 1.0);
    out.local = corner;
  } else {
    let a = to_ndc(item.a);
    let b = to_ndc(item.b);
    let along = (b.xy - a.xy) * frame.viewport.xy;
    let len = length(along);
    let dir = select(vec2f(1.0, 0.0), along / len, len > 1e-6);
    let across = vec2f(-dir.y, dir.x) * item.shape.x * px;
    let p = select(a.xy, b.xy, corner.x > 0.0);
    out.position = vec4f(p + corner.y * across, 0.0, 1.0);
    out.local = vec2f(0.0);
  }
  return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4f {
  let item = items[in.item];
  let r = length(in.local);
  if (r > 1.0) {
    discard;
  }
  // a dark rim, so a disc shows on a surface of its own colour
  let rim = select(1.0, 0.35, item.shape.y < 0.5 && r > 0.72);
  return vec4f(item.color.rgb * rim, 1.0);
}
