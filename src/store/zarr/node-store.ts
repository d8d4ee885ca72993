// The CLI's and tests' store for a location: an http(s) URL through our
// HttpStore (failures in the words of what was observed; retried by
// openStore), anything else a folder through @zarrita/storage's
// FileSystemStore (Node only; the page uses stores.ts and HttpStore).
import type { AsyncReadable } from '@zarrita/storage';
import FileSystemStore from '@zarrita/storage/fs';
import { existsSync, statSync } from 'node:fs';
import { resolve } from 'node:path';
import { StoreError } from './errors.ts';
import { HttpStore } from './http-store.ts';

export function isStoreUrl(location: string): boolean {
  return /^https?:\/\//i.test(location);
}

export function storeForLocation(location: string): AsyncReadable {
  if (isStoreUrl(location)) return new HttpStore(location);
  const path = resolve(location);
  if (!existsSync(path) || !statSync(path).isDirectory())
    throw new StoreError('unreachable', `${location}: no such folder (a Zarr store is a folder or an http(s) URL)`);
  return new FileSystemStore(path);
}
