// How a worker opens the same store again: stores that can be rebuilt from
// what postMessage carries (a URL, the dropped File objects, a directory
// handle). Others (a simulated link, a fault injector) have none, and their
// bricks are decoded on the main thread.
import type { AsyncReadable } from '@zarrita/storage';
import { HttpStore } from '../zarr/http-store.ts';
import { type BlobLike, DirectoryHandleStore, type DirectoryHandleLike, FileMapStore, MeteredStore } from '../zarr/stores.ts';

export type StoreSpec =
  | { kind: 'http'; url: string }
  | { kind: 'files'; files: Map<string, BlobLike> }
  | { kind: 'directory'; handle: DirectoryHandleLike };

/** The spec of `store` (through MeteredStore wrappers), or null when a worker cannot open it. */
export function storeSpecOf(store: AsyncReadable): StoreSpec | null {
  let s: AsyncReadable = store;
  while (s instanceof MeteredStore) s = s.inner;
  if (s instanceof HttpStore) return { kind: 'http', url: s.url };
  if (s instanceof FileMapStore) return { kind: 'files', files: new Map(s.files) };
  if (s instanceof DirectoryHandleStore) return { kind: 'directory', handle: s.root };
  return null;
}

export function storeFromSpec(spec: StoreSpec): AsyncReadable {
  if (spec.kind === 'http') return new HttpStore(spec.url);
  if (spec.kind === 'files') return new FileMapStore(spec.files);
  return new DirectoryHandleStore(spec.handle);
}
