// A zipped Zarr store (OME-Zarr's `.ozx`, RFC 9; any .zip holding a store)
// read in place with range reads: the end of central directory record (and
// its ZIP64 form) from the file's tail, then the central directory, then
// each entry's bytes when asked for. Stored entries (what RFC 9 asks for)
// are read as ranges, so a shard's index and inner chunks cost one small
// read each; deflated entries are inflated whole (DecompressionStream).
// Works over any reader of byte ranges: a local file (CLI), an http(s) URL
// (HttpStore's range requests), a dropped File (the page).
//
// Files are hostile: every offset and size read from the file is checked
// against the file's length and sane limits before anything is allocated,
// and a zip that breaks a rule is refused with a StoreError naming the file.
import type { AbsolutePath, AsyncReadable, GetOptions, RangeQuery } from '@zarrita/storage';
import { StoreError } from './errors.ts';

/** Byte ranges of one file. */
export interface ZipBytes {
  /** The last `length` bytes (all of them when the file is shorter). */
  tail(length: number, opts?: GetOptions): Promise<Uint8Array>;
  read(offset: number, length: number, opts?: GetOptions): Promise<Uint8Array>;
}

interface Entry {
  method: number;
  compressedSize: number;
  size: number;
  localHeader: number;
  nameLength: number;
  /** Where the entry's data starts, once its local header was read. */
  data?: number;
}

const EOCD = 0x06054b50;
const ZIP64_LOCATOR = 0x07064b50;
const ZIP64_EOCD = 0x06064b50;
const CENTRAL = 0x02014b50;
const LOCAL = 0x04034b50;
/** EOCD (22 B) + the longest comment (65535 B) + the ZIP64 locator (20 B). */
const TAIL_BYTES = 22 + 65535 + 20;
/** Sane limits: a central directory of at most 256 MiB and 8 Mi entries (a store of 8 Mi chunk files). */
const MAX_DIRECTORY_BYTES = 256 * 2 ** 20;
const MAX_ENTRIES = 8 * 2 ** 20;
/** An entry inflated whole: at most 1 GiB. */
const MAX_INFLATED = 2 ** 30;

export class ZipStore implements AsyncReadable {
  #entries: Promise<Map<string, Entry>> | null = null;
  /** Path of the store's root inside the zip ('' or 'name/'). */
  #prefix = '';
  #size = 0;

  constructor(
    readonly bytes: ZipBytes,
    /** The file, for messages. */
    readonly name: string,
  ) {}

  async get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    const e = (await this.#directory(opts)).get(this.#prefix + key.replace(/^\//, ''));
    if (!e) return undefined;
    const start = await this.#dataStart(key, e, opts);
    const raw = await this.bytes.read(start, e.compressedSize, opts);
    if (raw.length !== e.compressedSize) throw this.#bad(`${key.replace(/^\//, '')} is cut short`);
    return e.method === 0 ? raw : this.#inflate(key, e, raw);
  }

  async getRange(key: AbsolutePath, range: RangeQuery, opts?: GetOptions): Promise<Uint8Array | undefined> {
    const e = (await this.#directory(opts)).get(this.#prefix + key.replace(/^\//, ''));
    if (!e) return undefined;
    if (e.method !== 0) {
      const all = await this.get(key, opts);
      if (!all) return undefined;
      return 'suffixLength' in range
        ? all.subarray(Math.max(0, all.length - range.suffixLength))
        : all.subarray(range.offset, range.offset + range.length);
    }
    const start = await this.#dataStart(key, e, opts);
    const [from, length] =
      'suffixLength' in range
        ? [Math.max(0, e.size - range.suffixLength), Math.min(range.suffixLength, e.size)]
        : [range.offset, Math.max(0, Math.min(range.length, e.size - range.offset))];
    if (from > e.size) return new Uint8Array(0);
    const got = await this.bytes.read(start + from, length, opts);
    if (got.length !== length) throw this.#bad(`${key.replace(/^\//, '')} is cut short`);
    return got;
  }

  /** The central directory, read once (a failed read is tried again next time). */
  #directory(opts?: GetOptions): Promise<Map<string, Entry>> {
    if (!this.#entries) {
      this.#entries = this.#readDirectory(opts);
      this.#entries.catch(() => {
        this.#entries = null;
      });
    }
    return this.#entries;
  }

  /** A damaged zip (openStore and the brick readers put the store's name before the message). */
  #bad(what: string): StoreError {
    return new StoreError('corrupt', `not a readable zip (${what})`);
  }

  async #readDirectory(opts?: GetOptions): Promise<Map<string, Entry>> {
    const tail = await this.bytes.tail(TAIL_BYTES, opts);
    const view = new DataView(tail.buffer, tail.byteOffset, tail.byteLength);
    let at = -1;
    for (let i = tail.length - 22; i >= 0; i--) {
      if (view.getUint32(i, true) === EOCD && i + 22 + view.getUint16(i + 20, true) === tail.length) {
        at = i;
        break;
      }
    }
    if (at < 0) {
      throw new StoreError(
        'not-a-store',
        `${this.name}: not a zip file (no end of central directory record in its last ${tail.length} bytes)`,
      );
    }
    let entries = view.getUint16(at + 10, true);
    let dirSize = view.getUint32(at + 12, true);
    let dirOffset = view.getUint32(at + 16, true);
    // the file's length: where the EOCD ends, from the directory's end (known only when the tail is the whole file)
    let eocdAt: number;
    if (entries === 0xffff || dirSize === 0xffffffff || dirOffset === 0xffffffff) {
      // ZIP64: the locator right before the EOCD names the ZIP64 EOCD record
      if (at < 20 || view.getUint32(at - 20, true) !== ZIP64_LOCATOR) throw this.#bad('ZIP64 sizes without a ZIP64 locator');
      const recordAt = Number(view.getBigUint64(at - 12, true));
      const record = await this.bytes.read(recordAt, 56, opts);
      if (record.length < 56) throw this.#bad('its ZIP64 end record is past the end of the file');
      const r = new DataView(record.buffer, record.byteOffset, 56);
      if (r.getUint32(0, true) !== ZIP64_EOCD) throw this.#bad('no ZIP64 end record where its locator says');
      entries = Number(r.getBigUint64(32, true));
      dirSize = Number(r.getBigUint64(40, true));
      dirOffset = Number(r.getBigUint64(48, true));
      eocdAt = recordAt + 56 + 20;
    } else {
      eocdAt = dirOffset + dirSize;
    }
    this.#size = eocdAt + (tail.length - at);
    if (tail.length < TAIL_BYTES && this.#size !== tail.length)
      throw this.#bad(`its directory says ${this.#size} bytes, the file has ${tail.length}`);
    if (!Number.isSafeInteger(dirOffset) || dirOffset + dirSize > eocdAt) throw this.#bad('its central directory lies past its end');
    if (entries > MAX_ENTRIES) throw this.#bad(`${entries} entries, more than ${MAX_ENTRIES}`);
    if (dirSize > MAX_DIRECTORY_BYTES) throw this.#bad(`a central directory of ${dirSize} bytes, more than ${MAX_DIRECTORY_BYTES}`);
    if (dirSize < 46 * entries) throw this.#bad(`${entries} entries in a central directory of ${dirSize} bytes`);
    const dir = await this.bytes.read(dirOffset, dirSize, opts);
    if (dir.length !== dirSize) throw this.#bad('its central directory is cut short');
    const d = new DataView(dir.buffer, dir.byteOffset, dir.byteLength);
    const decoder = new TextDecoder();
    const map = new Map<string, Entry>();
    let p = 0;
    for (let n = 0; n < entries; n++) {
      if (p + 46 > dirSize || d.getUint32(p, true) !== CENTRAL) throw this.#bad(`central directory entry ${n} is damaged`);
      const method = d.getUint16(p + 10, true);
      let compressedSize = d.getUint32(p + 20, true);
      let size = d.getUint32(p + 24, true);
      const nameLength = d.getUint16(p + 28, true);
      const extraLength = d.getUint16(p + 30, true);
      const commentLength = d.getUint16(p + 32, true);
      let localHeader = d.getUint32(p + 42, true);
      const next = p + 46 + nameLength + extraLength + commentLength;
      if (next > dirSize) throw this.#bad(`central directory entry ${n} runs past the directory`);
      const name = decoder.decode(dir.subarray(p + 46, p + 46 + nameLength));
      // ZIP64 extended information: the 64-bit values of the fields that say 0xffffffff, in this order
      for (let x = p + 46 + nameLength; x + 4 <= p + 46 + nameLength + extraLength; ) {
        const id = d.getUint16(x, true);
        const len = d.getUint16(x + 2, true);
        if (id === 0x0001) {
          let v = x + 4;
          const take = () => {
            if (v + 8 > x + 4 + len) throw this.#bad(`entry ${name}: a short ZIP64 field`);
            const value = Number(d.getBigUint64(v, true));
            v += 8;
            return value;
          };
          if (size === 0xffffffff) size = take();
          if (compressedSize === 0xffffffff) compressedSize = take();
          if (localHeader === 0xffffffff) localHeader = take();
        }
        x += 4 + len;
      }
      if (method !== 0 && method !== 8)
        throw new StoreError('codec', `${this.name}: entry ${name} is compressed with zip method ${method} (stored and deflate are read)`);
      if (localHeader + 30 + nameLength + compressedSize > dirOffset) throw this.#bad(`entry ${name} lies past the file's data`);
      if (!name.endsWith('/')) map.set(name, { method, compressedSize, size, localHeader, nameLength });
      p = next;
    }
    // a store zipped with its folder: its root one level down
    if (!map.has('zarr.json') && !map.has('.zgroup') && !map.has('.zarray')) {
      const roots = [...map.keys()].filter((k) => /^[^/]+\/(zarr\.json|\.zgroup|\.zarray)$/.test(k));
      if (roots.length === 1) this.#prefix = roots[0].slice(0, roots[0].indexOf('/') + 1);
    }
    return map;
  }

  /** Where an entry's data starts: past its local header (whose extra field may differ from the directory's). */
  async #dataStart(key: string, e: Entry, opts?: GetOptions): Promise<number> {
    if (e.data !== undefined) return e.data;
    const head = await this.bytes.read(e.localHeader, 30, opts);
    const h = new DataView(head.buffer, head.byteOffset, head.byteLength);
    if (head.length < 30 || h.getUint32(0, true) !== LOCAL) throw this.#bad(`no local header for ${key.replace(/^\//, '')}`);
    const start = e.localHeader + 30 + h.getUint16(26, true) + h.getUint16(28, true);
    if (start + e.compressedSize > this.#size) throw this.#bad(`${key.replace(/^\//, '')} runs past the end of the file`);
    e.data = start;
    return start;
  }

  async #inflate(key: string, e: Entry, raw: Uint8Array): Promise<Uint8Array> {
    if (e.size > MAX_INFLATED) throw this.#bad(`${key.replace(/^\//, '')} inflates to ${e.size} bytes, more than ${MAX_INFLATED}`);
    try {
      const stream = new Blob([raw as Uint8Array<ArrayBuffer>]).stream().pipeThrough(new DecompressionStream('deflate-raw'));
      const out = new Uint8Array(await new Response(stream).arrayBuffer());
      if (out.length !== e.size) throw new Error(`${out.length} bytes, the directory says ${e.size}`);
      return out;
    } catch (err) {
      throw this.#bad(`${key.replace(/^\//, '')} does not inflate: ${(err as Error).message}`);
    }
  }
}

/** Whether a location names a zipped store (by its extension). */
export function isZipStoreName(location: string): boolean {
  return /\.(ozx|zip)$/i.test(location.replace(/[?#].*$/, ''));
}

/** A File's byte ranges (the page's dropped or picked .ozx). */
export function fileZipBytes(file: Blob): ZipBytes {
  return {
    tail: async (n) => new Uint8Array(await file.slice(Math.max(0, file.size - n)).arrayBuffer()),
    read: async (offset, length) => new Uint8Array(await file.slice(offset, offset + length).arrayBuffer()),
  };
}

/** One key of a store with range reads (an HttpStore over the file's folder): a zip at a URL. */
export function storeZipBytes(store: AsyncReadable, key: AbsolutePath, name: string): ZipBytes {
  const need = async (got: Promise<Uint8Array | undefined> | undefined) => {
    const bytes = got ? await got : undefined;
    if (!bytes) throw new StoreError('not-found', `${name}: no such file (HTTP 404)`);
    return bytes;
  };
  if (!store.getRange) throw new Error(`${name}: its store cannot read byte ranges`);
  return {
    tail: (n, opts) => need(store.getRange!(key, { suffixLength: n }, opts)),
    read: (offset, length, opts) =>
      need(length === 0 ? Promise.resolve(new Uint8Array(0)) : store.getRange!(key, { offset, length }, opts)),
  };
}
