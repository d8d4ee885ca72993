// Turns a GPU-written element count into indirect dispatch arguments for
// kernels of 64 invocations per workgroup laid out on a 2D grid (x <= MAX_WG):
// args = [x, y, 1, count]. One invocation does the work; the workgroup size is
// 64 only to follow the project rule.

override MAX_WG: u32 = 65535u;

struct CountRef {
  word: u32,  // index of the count in count_words
}

@group(0) @binding(0) var<storage, read> count_words: array<u32>;
@group(0) @binding(1) var<uniform> count_ref: CountRef;
@group(0) @binding(2) var<storage, read_write> args_out: array<u32>;

fn ceil_div(a: u32, b: u32) -> u32 {
  return a / b + select(0u, 1u, a % b != 0u);
}

@compute @workgroup_size(64)
fn indirect_args(@builtin(local_invocation_index) lid: u32) {
  if (lid != 0u) { return; }
  let count = count_words[count_ref.word];
  let groups = ceil_div(count, 64u);
  let y = max(1u, ceil_div(groups, MAX_WG));
  args_out[0] = ceil_div(groups, y);
  args_out[1] = y;
  args_out[2] = 1u;
  args_out[3] = count;
}
