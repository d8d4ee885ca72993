// Indirect dispatch arguments from GPU-side counts. A "dispatch record" is 8
// u32 words in a params buffer: [n, units, capacity, count_in, x, y, z, extra].
// The host copies the count into count_in; `setup_dispatch` clamps it to
// capacity, counts units of work (chunks of elements, one per invocation)
// and writes the grid (x, y, z; dispatch_grid of shaders/common/grid.wgsl)
// that dispatchWorkgroupsIndirect reads at byte 16 of the record. Kernels
// read n and units as a uniform and skip invocations past `units` (the 2D
// grid can overshoot by less than a row).
//
// One-thread kernel that fills LEVELS dispatch records, 64 words (256
// bytes, the uniform offset alignment) apart. Record 0 takes
// the copied-in count. Each level's n elements form `units` chunks of CHUNK
// elements (one per invocation), dispatched as ceil(units / WG) workgroups;
// record l+1 has n = units of record l, which is what a multi-level scan
// needs (one partial sum per chunk).

override CHUNK: u32;
override WG: u32;
override LEVELS: u32 = 1u;
// Word 7 of record 0 gets units * TABLE_ROWS: the size of a table with that
// many rows per unit (the radix sort's digit histograms), used as a GPU count.
override TABLE_ROWS: u32 = 0u;

@group(0) @binding(0) var<storage, read_write> records: array<u32>;

@compute @workgroup_size(1)
fn setup_dispatch() {
  var n = min(records[3], records[2]);
  for (var l = 0u; l < LEVELS; l++) {
    let r = l * 64u;
    let units = ceil_div(n, CHUNK);
    let grid = dispatch_grid(ceil_div(units, WG));
    records[r] = n;
    records[r + 1u] = units;
    records[r + 4u] = grid.x;
    records[r + 5u] = grid.y;
    records[r + 6u] = grid.z;
    if (l == 0u) {
      records[7] = units * TABLE_ROWS;
    }
    n = units;
  }
}
