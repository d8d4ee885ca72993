// Indirect dispatch arguments from a GPU-written element count: one
// invocation (an argument kernel) reads the count (word `count_ref.word` of
// the bound storage range, so it may sit at any 4-byte offset of the
// caller's buffer) and writes [x, y, z, count] with dispatch_grid
// (shaders/common/grid.wgsl): ceil(count / ITEMS) workgroups, 1D, 2D past
// MAX_WG_PER_DIM, 3D past its square. Kernels dispatched with them rebuild
// the linear workgroup index as x + nx * (y + ny * z) (grid_workgroup_index)
// and may read the count at word 3.

override ITEMS: u32 = 64u;

struct CountRef {
  word: u32,
}

@group(0) @binding(0) var<storage, read> count_words: array<u32>;
@group(0) @binding(1) var<uniform> count_ref: CountRef;
@group(0) @binding(2) var<storage, read_write> args_out: array<u32, 4>;

@compute @workgroup_size(1)
fn indirect_args() {
  let count = count_words[count_ref.word];
  let g = dispatch_grid(ceil_div(count, ITEMS));
  args_out[0] = g.x;
  args_out[1] = g.y;
  args_out[2] = g.z;
  args_out[3] = count;
}
