// Stable LSD radix sort by u32 key with u32 values, 4 bits per pass,
// barrier-free. Each invocation owns a chunk of CHUNK consecutive elements:
// `histogram` counts the chunk's digits into table[d * units + chunk]
// (digit-major), an exclusive scan of the table (ExclusiveScan) turns that
// into the first output position of each (digit, chunk), and `scatter` walks
// the chunk in order writing each element at its digit's next position.
// Chunks are in index order and each is walked in order, so equal digits
// keep their order: the sort is stable. Descending order complements the
// digit (d ^ mask), so it is stable too and needs no reverse pass.
// Composed after radix_sort_common.wgsl (uniforms, bindings, digit()).

override WG: u32 = 64u;
override CHUNK: u32 = 128u; // at most 255: per-digit counters are 8-bit lanes

/** One count for the key's digit, in the 8-bit lane layout of `histogram`. */
fn count_digit(key: u32) -> vec4u {
  let d = digit(key);
  return select(vec4u(0u), vec4u(1u << ((d & 3u) * 8u)), vec4u(d >> 2u) == vec4u(0u, 1u, 2u, 3u));
}

@compute @workgroup_size(WG)
fn histogram(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let c = grid_invocation_index(wid, nwg, lid, WG);
  let units = sort.units;
  if (c >= units) {
    return;
  }
  let begin = c * CHUNK;
  let len = min(sort.n - begin, CHUNK);
  // 16 counters as 8-bit lanes of 4 words: no dynamically indexed array.
  // Four keys per iteration: loop overhead dominates on CPU implementations.
  var counts = vec4u(0u);
  var j = 0u;
  for (; j + 4u <= len; j += 4u) {
    let i = begin + j;
    counts += count_digit(keys_in[i]) + count_digit(keys_in[i + 1u]) + count_digit(keys_in[i + 2u]) + count_digit(keys_in[i + 3u]);
  }
  for (; j < len; j++) {
    counts += count_digit(keys_in[begin + j]);
  }
  for (var d = 0u; d < 16u; d++) {
    histograms[d * units + c] = (counts[d >> 2u] >> ((d & 3u) * 8u)) & 255u;
  }
}

/** Writes element i at its digit's next position and advances that position. */
fn place(next: ptr<function, array<u32, 16>>, i: u32) {
  let key = keys_in[i];
  let d = digit(key);
  let p = (*next)[d];
  (*next)[d] = p + 1u;
  keys_out[p] = key;
  values_out[p] = values_in[i];
}

@compute @workgroup_size(WG)
fn scatter(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
           @builtin(local_invocation_index) lid: u32) {
  let c = grid_invocation_index(wid, nwg, lid, WG);
  let units = sort.units;
  if (c >= units) {
    return;
  }
  var next: array<u32, 16>;
  for (var d = 0u; d < 16u; d++) {
    next[d] = offsets[d * units + c];
  }
  let begin = c * CHUNK;
  let len = min(sort.n - begin, CHUNK);
  var j = 0u;
  for (; j + 4u <= len; j += 4u) {
    let i = begin + j;
    place(&next, i);
    place(&next, i + 1u);
    place(&next, i + 2u);
    place(&next, i + 3u);
  }
  for (; j < len; j++) {
    place(&next, begin + j);
  }
}

// Copies the sorted result back when an in-place sort ran an odd number of
// passes (it ended in scratch).
@compute @workgroup_size(WG)
fn copy_back(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let c = grid_invocation_index(wid, nwg, lid, WG);
  if (c >= sort.units) {
    return;
  }
  let begin = c * CHUNK;
  let len = min(sort.n - begin, CHUNK);
  for (var j = 0u; j < len; j++) {
    keys_out[begin + j] = keys_in[begin + j];
    values_out[begin + j] = values_in[begin + j];
  }
}
