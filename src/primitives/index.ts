// GPU data-parallel primitives: exclusive scan, stream compaction (values and
// IDs), radix sort-by-key and indirect dispatch arguments, all driven by
// element counts that live in GPU buffers. See README.md in this folder.
export type { GpuCount } from '../gpu/buffer-ref.ts';
export { HOST_COUNT_SLOTS, toGpuCount, type CountLike } from './count.ts';
export type { PrimitiveOptions } from './dispatch-records.ts';
export { IndirectArgs, type IndirectArgsEncodeArgs, type IndirectArgsOptions } from './indirect.ts';
export { ExclusiveScan, type ExclusiveScanArgs, type ExclusiveScanOptions } from './scan.ts';
export { StreamCompact, StreamCompactIds, type CompactOptions, type StreamCompactArgs, type StreamCompactIdsArgs } from './compact.ts';
export { RadixSortByKey, type RadixSortArgs, type RadixSortOptions } from './sort.ts';
