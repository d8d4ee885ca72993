// The page's store view (`?store=URL`): opens a Zarr store of zfp chunks
// (src/store/), then shows its levels coarsest first, each one replacing
// the coarser surface once it is on the GPU, with a progress line (level,
// chunks done / needed, bytes) and a panel (levels, network, memory).
// Interim: until the GPU chunk pool (ChunkedVolume) is merged, a level is
// fetched whole and assembled into one zfp stream (src/store/assemble.ts,
// no decode), then opened through the page's usual loader; a level whose
// stream exceeds half the memory budget is not loaded, and the panel says so.
// Errors keep the current surface (the loader's rule) and name the store.
import type { AsyncReadable } from '@zarrita/storage';
import { FetchStore } from 'zarrita';
import type { GpuContext } from '../../gpu/device.ts';
import { assembleLevelStream, assemblyLimit } from '../../store/assemble.ts';
import { ChunkFetcher } from '../../store/fetch/chunk-fetcher.ts';
import type { ChunkIndex } from '../../store/types.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { openZfpStore, type ZfpStore } from '../../store/zarr/open-store.ts';
import { MeteredStore } from '../../store/zarr/stores.ts';
import { inspectVolumeFile, openVolumeFile, type OpenedVolume } from '../../volume/open-volume.ts';

type Produce = (signal: AbortSignal, progress: (text: string, f?: number) => void) => Promise<OpenedVolume | undefined>;

export interface StoreViewDeps {
  gpu: GpuContext;
  /** The loader's install path (VolumeLoader.loadProduced). */
  load(what: string, produce: Produce): Promise<void>;
  /** Before a finer level replaces the shown one: carry the isovalue and the camera over. */
  keepView(): void;
  /** True while the loader opens something (the user's file): a store level never cancels it. */
  busy(): boolean;
  /** True when the last load installed its volume. */
  installed(name: string): boolean;
  budgetBytes(): number;
  onError(message: string): void;
  /** The finest level to show (a link's #level=), or undefined for level 0. */
  linkLevel(): number | undefined;
  /** The level now shown, for the link. */
  onLevel(level: number): void;
  /** Where the page tests read the figures (window.zfpisoStore). */
  publish(state: StorePageState): void;
  line: HTMLElement;
  panel: HTMLElement;
}

export interface StorePageState {
  url: string;
  levels: { level: number; dims: number[]; chunks: number; chunkBytes: number; storedBytes: number }[];
  shownLevel: number | null;
  /** Levels in the order they replaced each other on screen. */
  shownLevels: number[];
  done: boolean;
  bytesFetched: number;
  chunkBytesFetched: number;
  requests: number;
  chunksFetched: number;
  reason: string | null;
}

const mib = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;

export class StoreView {
  #gen = 0;
  constructor(private readonly d: StoreViewDeps) {}

  /** A store by URL (same origin, or another one with CORS). */
  open(url: string): Promise<void> {
    return this.openStore(new FetchStore(new URL(url, location.href).href), url);
  }

  /** Any store (a dropped or picked folder: zarr/stores.ts); `url` names it in messages. */
  async openStore(source: AsyncReadable, url: string): Promise<void> {
    const gen = ++this.#gen;
    const metered = new MeteredStore(source);
    let store: ZfpStore;
    this.#line(`Opening ${url}…`);
    try {
      store = await openZfpStore(metered, url);
    } catch (e) {
      this.#line('');
      this.d.onError(e instanceof StoreError ? e.message : `${url}: ${(e as Error).message}`);
      return;
    }
    const st: StorePageState = {
      url, shownLevel: null, shownLevels: [], done: false, bytesFetched: 0, chunkBytesFetched: 0, requests: 0, chunksFetched: 0, reason: null,
      levels: store.levels.map((l) => ({ level: l.index, dims: l.layout.dims, chunks: l.chunkCount, chunkBytes: l.layout.chunkBytes, storedBytes: l.storedBytes })),
    };
    for (const note of store.notes) this.d.onError(`${url}: ${note}`);
    const fetcher = new ChunkFetcher(store, { maxInFlight: 8 });
    const update = () => {
      const c = fetcher.counters;
      Object.assign(st, { bytesFetched: metered.meter.bytes, chunkBytesFetched: c.bytesFetched, requests: metered.meter.requests });
      this.#panel(store, st, fetcher);
      this.d.publish({ ...st });
    };
    update();
    let lastName: string | null = null;
    const finest = Math.min(this.d.linkLevel() ?? 0, store.levels.length - 1);
    if (finest > 0) st.reason = `the link asks for level ${finest}`;
    for (let L = store.levels.length - 1; L >= finest && gen === this.#gen; L--) {
      const lv = store.levels[L];
      const streamBytes = lv.storedBytes;
      const limit = assemblyLimit(lv.layout, 2 ** 31); // one CPU buffer before upload
      if (limit) {
        st.reason = `${limit}; level ${L + 1} stays`;
        break;
      }
      if (streamBytes > this.d.budgetBytes() / 2) {
        st.reason = `level ${L} (${mib(streamBytes)} of chunks) exceeds half the memory budget (${mib(this.d.budgetBytes())}); level ${L + 1} stays`;
        break;
      }
      const chunks = new Map<ChunkIndex, Uint8Array>();
      let failure: StoreError | null = null;
      const offChunk = fetcher.onChunk((_l, c, b) => {
        chunks.set(c, b);
        st.chunksFetched++;
        this.#line(`${url}: level ${L}, ${chunks.size} / ${lv.chunkCount} chunks, ${mib(metered.meter.bytes)}`);
        update();
      });
      const offError = fetcher.onError((_l, _c, e) => { failure ??= e; });
      fetcher.want(L, Array.from({ length: lv.chunkCount }, (_, i) => i));
      await fetcher.idle();
      offChunk();
      offError();
      if (gen !== this.#gen) return;
      if (failure) {
        st.reason = (failure as StoreError).message;
        this.d.onError((failure as StoreError).message);
        break;
      }
      // The user opened another volume meanwhile: this store no longer owns the view.
      if ((lastName !== null && !this.d.installed(lastName)) || this.d.busy()) {
        fetcher.cancelAll();
        return;
      }
      const bytes = assembleLevelStream(lv.layout, (c) => chunks.get(c)!);
      const name = `${url} level ${L}`;
      if (st.shownLevel !== null) this.d.keepView();
      await this.d.load(name, async () => {
        const facts = await inspectVolumeFile(`${lv.layout.dims.join('x')}.zfp`, bytes);
        const opened = await openVolumeFile(this.d.gpu.device, facts, bytes);
        const s = 2 ** L;
        opened.name = name;
        opened.fileName = name;
        opened.spacing = [store.voxelSize[0] * s, store.voxelSize[1] * s, store.voxelSize[2] * s];
        return opened;
      });
      if (gen !== this.#gen) return;
      if (!this.d.installed(name)) {
        st.reason = `level ${L} could not be shown (see the message); level ${st.shownLevel ?? 'none'} stays`;
        break;
      }
      lastName = name;
      st.shownLevel = L;
      st.shownLevels.push(L);
      this.d.onLevel(L);
      update();
    }
    st.done = true;
    this.#line(st.reason ? `${url}: level ${st.shownLevel} shown; ${st.reason}` : `${url}: level ${st.shownLevel} (full resolution), ${mib(metered.meter.bytes)} fetched`);
    update();
  }

  #line(text: string): void {
    this.d.line.hidden = text === '';
    this.d.line.textContent = text;
  }

  #panel(store: ZfpStore, st: StorePageState, fetcher: ChunkFetcher): void {
    const c = fetcher.counters;
    const rows = store.levels.map((l) => `<tr${st.shownLevel === l.index ? ' class="shown"' : ''}><td>${l.index}</td><td>${l.layout.dims.join('×')}</td><td>${l.chunkCount}</td><td>${mib(l.storedBytes)}</td></tr>`).join('');
    this.d.panel.hidden = false;
    this.d.panel.innerHTML =
      `<h2>Store</h2><table class="store-levels"><thead><tr><th>level</th><th>dims</th><th>chunks</th><th>bytes</th></tr></thead><tbody>${rows}</tbody></table>` +
      `<dl class="store-network">` +
      `<dt>fetched</dt><dd data-k="bytes">${mib(st.bytesFetched)}</dd>` +
      `<dt>requests</dt><dd data-k="requests">${st.requests}</dd>` +
      `<dt>chunks</dt><dd data-k="chunks">${st.chunksFetched}</dd>` +
      `<dt>in flight</dt><dd>${c.inFlight}</dd><dt>aborted</dt><dd>${c.aborted}</dd><dt>cache hits</dt><dd>${c.cacheHits}</dd>` +
      `<dt>throughput</dt><dd>${mib(c.throughputBytesPerSecond)}/s</dd>` +
      `<dt>CPU cache</dt><dd>${mib(c.cacheBytes)} of ${mib(c.cacheCapacityBytes)}</dd>` +
      `<dt>budget</dt><dd>${mib(this.d.budgetBytes())}</dd>` +
      (st.reason ? `<dt>note</dt><dd data-k="reason">${st.reason.replace(/</g, '&lt;')}</dd>` : '') +
      `</dl>`;
  }
}
