// The CLI's and tests' store for a location: an http(s) URL through our
// HttpStore (failures in the words of what was observed; retried by
// openStore), anything else a folder through @zarrita/storage's
// FileSystemStore (Node only; the page uses stores.ts and HttpStore); a
// zipped store (.ozx, .zip) by URL or file through ZipStore.
import type { AsyncReadable } from '@zarrita/storage';
import FileSystemStore from '@zarrita/storage/fs';
import { existsSync, statSync } from 'node:fs';
import { open } from 'node:fs/promises';
import { resolve } from 'node:path';
import { StoreError } from './errors.ts';
import { HttpStore } from './http-store.ts';
import { isZipStoreName, storeZipBytes, ZipStore, type ZipBytes } from './zip-store.ts';

export function isStoreUrl(location: string): boolean {
  return /^https?:\/\//i.test(location);
}

export function storeForLocation(location: string): AsyncReadable {
  if (isZipStoreName(location)) {
    if (isStoreUrl(location)) {
      const url = new URL(location);
      const file = url.pathname.slice(url.pathname.lastIndexOf('/') + 1);
      return new ZipStore(storeZipBytes(new HttpStore(new URL('.', url).href), `/${file}`, location), location);
    }
    const path = resolve(location);
    if (!existsSync(path) || !statSync(path).isFile()) throw new StoreError('unreachable', `${location}: no such file`);
    return new ZipStore(fileBytes(path), location);
  }
  if (isStoreUrl(location)) return new HttpStore(location);
  const path = resolve(location);
  if (!existsSync(path) || !statSync(path).isDirectory())
    throw new StoreError('unreachable', `${location}: no such folder (a Zarr store is a folder or an http(s) URL)`);
  return new FileSystemStore(path);
}

/** A local file's byte ranges (its length read once). */
function fileBytes(path: string): ZipBytes {
  const read = async (offset: number, length: number) => {
    const f = await open(path, 'r');
    try {
      const size = (await f.stat()).size;
      const from = Math.max(0, Math.min(offset, size));
      const n = Math.max(0, Math.min(length, size - from));
      const out = new Uint8Array(n);
      let got = 0;
      while (got < n) {
        const { bytesRead } = await f.read(out, got, n - got, from + got);
        if (bytesRead === 0) break;
        got += bytesRead;
      }
      return out.subarray(0, got);
    } finally {
      await f.close();
    }
  };
  return {
    tail: async (n) => {
      const size = statSync(path).size;
      return read(Math.max(0, size - n), Math.min(n, size));
    },
    read,
  };
}
