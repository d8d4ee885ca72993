// Stores in zarrita's interface (`get` / `getRange` of @zarrita/storage):
// the page's read-only stores over a dropped folder or a picked directory,
// a metering wrapper (bytes and requests, for the panel and the CLI's
// records) and a simulated network link (benchmarks).
import type { AbsolutePath, AsyncReadable, GetOptions, RangeQuery } from '@zarrita/storage';

/** Bytes and requests that went through a store, metadata and chunks alike. */
export interface StoreMeter {
  bytes: number;
  requests: number;
}

function sliceRange(bytes: Uint8Array, range: RangeQuery): Uint8Array {
  if ('suffixLength' in range) return bytes.subarray(Math.max(0, bytes.length - range.suffixLength));
  return bytes.subarray(range.offset, range.offset + range.length);
}

function aborted(signal: AbortSignal | undefined): void {
  if (signal?.aborted) throw signal.reason ?? new DOMException('aborted', 'AbortError');
}

/** Counts every byte and request that reaches the inner store. */
export class MeteredStore implements AsyncReadable {
  /** `meter`: counts shared with another store (a ranges sidecar counts with its store). */
  constructor(
    readonly inner: AsyncReadable,
    readonly meter: StoreMeter = { bytes: 0, requests: 0 },
  ) {}
  async get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    this.meter.requests++;
    const bytes = await this.inner.get(key, opts);
    this.meter.bytes += bytes?.length ?? 0;
    return bytes;
  }
  async getRange(key: AbsolutePath, range: RangeQuery, opts?: GetOptions): Promise<Uint8Array | undefined> {
    this.meter.requests++;
    const bytes = this.inner.getRange
      ? await this.inner.getRange(key, range, opts)
      : await this.inner.get(key, opts).then((b) => b && sliceRange(b, range));
    this.meter.bytes += bytes?.length ?? 0;
    return bytes;
  }
}

export interface LinkOptions {
  /** Bandwidth shared by all requests, megabits per second. */
  mbitPerSecond: number;
  /** Added to every request (one round trip). */
  latencyMs: number;
}

/**
 * A simulated link in front of a store (benchmarks): every request waits the
 * latency, then its bytes go through one shared pipe at the given bandwidth
 * (requests queue for the pipe, as on a real link). Aborts are honoured.
 */
export class SimulatedLinkStore implements AsyncReadable {
  #pipeFreeAt = 0;
  constructor(
    readonly inner: AsyncReadable,
    readonly link: LinkOptions,
  ) {}
  async #delay(bytes: number, signal?: AbortSignal): Promise<void> {
    const now = performance.now();
    const start = Math.max(now + this.link.latencyMs, this.#pipeFreeAt);
    const end = start + (bytes * 8) / (this.link.mbitPerSecond * 1000);
    this.#pipeFreeAt = end;
    await new Promise<void>((resolve, reject) => {
      const timer = setTimeout(resolve, end - now);
      signal?.addEventListener(
        'abort',
        () => {
          clearTimeout(timer);
          reject(signal.reason ?? new DOMException('aborted', 'AbortError'));
        },
        { once: true },
      );
    });
  }
  async get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    aborted(opts?.signal);
    const bytes = await this.inner.get(key, opts);
    await this.#delay(bytes?.length ?? 0, opts?.signal);
    return bytes;
  }
  async getRange(key: AbsolutePath, range: RangeQuery, opts?: GetOptions): Promise<Uint8Array | undefined> {
    aborted(opts?.signal);
    const bytes = this.inner.getRange
      ? await this.inner.getRange(key, range, opts)
      : await this.inner.get(key, opts).then((b) => b && sliceRange(b, range));
    await this.#delay(bytes?.length ?? 0, opts?.signal);
    return bytes;
  }
}

/** Something with the bytes of a file, read in parts (a DOM File or Blob). */
export interface BlobLike {
  readonly size: number;
  slice(start?: number, end?: number): { arrayBuffer(): Promise<ArrayBuffer> };
}

async function readBlob(blob: BlobLike, range?: RangeQuery): Promise<Uint8Array> {
  if (!range) return new Uint8Array(await blob.slice().arrayBuffer());
  if ('suffixLength' in range) return new Uint8Array(await blob.slice(Math.max(0, blob.size - range.suffixLength)).arrayBuffer());
  return new Uint8Array(await blob.slice(range.offset, range.offset + range.length).arrayBuffer());
}

/**
 * A store over files dropped on the page or picked with <input webkitdirectory>:
 * keys are paths relative to the `.zarr` folder. Only the parts asked for are
 * read (chunks stay on disk until needed).
 */
export class FileMapStore implements AsyncReadable {
  constructor(readonly files: ReadonlyMap<string, BlobLike>) {}
  async get(key: AbsolutePath): Promise<Uint8Array | undefined> {
    const file = this.files.get(key.slice(1));
    return file ? readBlob(file) : undefined;
  }
  async getRange(key: AbsolutePath, range: RangeQuery): Promise<Uint8Array | undefined> {
    const file = this.files.get(key.slice(1));
    return file ? readBlob(file, range) : undefined;
  }
}

/** The part of FileSystemDirectoryHandle this store uses (absent from older DOM typings). */
export interface DirectoryHandleLike {
  readonly name: string;
  getDirectoryHandle(name: string): Promise<DirectoryHandleLike>;
  getFileHandle(name: string): Promise<{ getFile(): Promise<BlobLike> }>;
}

/** A store over a picked or dropped directory handle (File System Access API). */
export class DirectoryHandleStore implements AsyncReadable {
  constructor(readonly root: DirectoryHandleLike) {}
  async #file(key: AbsolutePath): Promise<BlobLike | undefined> {
    const parts = key.slice(1).split('/');
    let dir = this.root;
    try {
      for (const part of parts.slice(0, -1)) dir = await dir.getDirectoryHandle(part);
      return await (await dir.getFileHandle(parts[parts.length - 1])).getFile();
    } catch (e) {
      if ((e as { name?: string }).name === 'NotFoundError' || (e as { name?: string }).name === 'TypeMismatchError') return undefined;
      throw e;
    }
  }
  async get(key: AbsolutePath): Promise<Uint8Array | undefined> {
    const file = await this.#file(key);
    return file ? readBlob(file) : undefined;
  }
  async getRange(key: AbsolutePath, range: RangeQuery): Promise<Uint8Array | undefined> {
    const file = await this.#file(key);
    return file ? readBlob(file, range) : undefined;
  }
}
