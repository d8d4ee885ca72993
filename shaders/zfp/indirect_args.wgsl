// Turns a GPU-written element count into indirect dispatch arguments for
// kernels of 64 invocations per workgroup laid out on a 2D grid (x <= 65535):
// args = [x, y, 1, count]. One invocation; its workgroup size is 64 only to
// follow the project rule, the other 63 invocations do nothing.

struct CountRef {
  word: u32,  // index of the count in count_words
}

@group(0) @binding(0) var<storage, read> count_words: array<u32>;
@group(0) @binding(1) var<uniform> count_ref: CountRef;
@group(0) @binding(2) var<storage, read_write> args_out: array<u32>;

@compute @workgroup_size(64)
fn indirect_args(@builtin(local_invocation_index) lid: u32) {
  if (lid != 0u) { return; }
  let count = count_words[count_ref.word];
  let groups = (count + 63u) / 64u;
  let y = (groups + 65534u) / 65535u;
  let x = select((groups + y - 1u) / y, 0u, groups == 0u);
  args_out[0] = x;
  args_out[1] = max(y, 1u);
  args_out[2] = 1u;
  args_out[3] = count;
}
