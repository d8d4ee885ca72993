// Shared by both radix sort kernel families (radix_sort.wgsl, emulator path;
// radix_sort_tiled.wgsl, GPU path; src/primitives/sort.ts composes this first):
// the per-sort and per-pass uniforms, the one bind group layout and the digit
// of a key in the current pass.

struct Sort {
  n: u32,
  units: u32,
  capacity: u32,
  count_in: u32,
}

struct Pass {
  shift: u32,
  mask: u32, // 15, or fewer bits in the last pass when keyBits is not a multiple of 4
  flip: u32, // mask for descending, 0 for ascending
}

@group(0) @binding(0) var<uniform> sort: Sort;
@group(0) @binding(1) var<uniform> pass_: Pass;
@group(0) @binding(2) var<storage, read> keys_in: array<u32>;
@group(0) @binding(3) var<storage, read> values_in: array<u32>;
@group(0) @binding(4) var<storage, read_write> histograms: array<u32>;
@group(0) @binding(5) var<storage, read> offsets: array<u32>;
@group(0) @binding(6) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(7) var<storage, read_write> values_out: array<u32>;

fn digit(key: u32) -> u32 {
  return ((key >> pass_.shift) & pass_.mask) ^ pass_.flip;
}
