// The Store section of the panel: the levels (dims, chunks, bytes, what was
// fetched of each), the network (bytes, requests, in flight, aborted, cache
// hits, throughput, retries) and the GPU memory, counted where it is made
// (pools, per-level buffers, cache, vertices, against the budget).
// StorePageState is also what the page tests read (window.zfpisoStore).
import type { FetchCounters } from '../../store/fetch/chunk-fetcher.ts';
import type { ZfpStore } from '../../store/zarr/open-store.ts';

export interface StorePageState {
  url: string;
  levels: {
    level: number;
    dims: number[];
    chunks: number;
    chunkBytes: number;
    storedBytes: number;
    chunksFetched: number;
    chunkBytesFetched: number;
  }[];
  shownLevel: number | null;
  /** Levels in the order they replaced each other on screen. */
  shownLevels: number[];
  /** The current isovalue's refinement has ended (finest level shown, or stopped with a reason). */
  done: boolean;
  /** Everything through the store: metadata, range arrays, shard indexes, chunks. */
  bytesFetched: number;
  chunkBytesFetched: number;
  requests: number;
  /** Distinct chunks fetched (all levels). */
  chunksFetched: number;
  reason: string | null;
  /** Requests tried again after a transient failure, and requests that failed for good (after their deadline). */
  retries: number;
  failedRequests: number;
  /** GPU bytes held (counted where they are made): pools of compressed chunks, surfaces (of which cache and vertices), against the budget. */
  gpu: { pools: number; surfaces: number; cache: number; vertices: number; total: number; peak: number; budget: number };
}

const mib = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;
const escapeHtml = (s: string) => s.replace(/&/g, '&amp;').replace(/</g, '&lt;');

export function renderStorePanel(panel: HTMLElement, store: ZfpStore, st: StorePageState, c: FetchCounters): void {
  const rows = st.levels
    .map(
      (l) =>
        `<tr${st.shownLevel === l.level ? ' class="shown"' : ''}><td>${l.level}</td><td>${l.dims.join('×')}</td><td>${l.chunksFetched} / ${l.chunks}</td><td>${mib(l.storedBytes)}</td></tr>`,
    )
    .join('');
  panel.hidden = false;
  panel.innerHTML =
    `<h2>Store</h2><p class="store-name">${escapeHtml(store.name)}</p>` +
    `<table class="store-levels"><thead><tr><th>level</th><th>dims</th><th>chunks fetched</th><th>stored</th></tr></thead><tbody>${rows}</tbody></table>` +
    `<dl class="store-network">` +
    `<dt>fetched</dt><dd data-k="bytes">${mib(st.bytesFetched)}</dd>` +
    `<dt>requests</dt><dd data-k="requests">${st.requests}</dd>` +
    `<dt>chunks</dt><dd data-k="chunks">${st.chunksFetched}</dd>` +
    `<dt>in flight</dt><dd>${c.inFlight}</dd><dt>aborted</dt><dd data-k="aborted">${c.aborted}</dd><dt>cache hits</dt><dd>${c.cacheHits}</dd>` +
    `<dt>throughput</dt><dd>${mib(c.throughputBytesPerSecond)}/s</dd>` +
    `<dt>retried</dt><dd data-k="retries">${st.retries}${st.failedRequests ? ` (${st.failedRequests} failed)` : ''}</dd>` +
    `<dt>CPU cache</dt><dd>${mib(c.cacheBytes)} of ${mib(c.cacheCapacityBytes)}</dd>` +
    `<dt>GPU pools</dt><dd data-k="pools">${mib(st.gpu.pools)}</dd>` +
    `<dt>GPU cache</dt><dd data-k="cache">${mib(st.gpu.cache)}</dd>` +
    `<dt>GPU vertices</dt><dd data-k="vertices">${mib(st.gpu.vertices)}</dd>` +
    `<dt>GPU per level</dt><dd data-k="level-state">${mib(Math.max(0, st.gpu.surfaces - st.gpu.cache - st.gpu.vertices))}</dd>` +
    `<dt>GPU total</dt><dd data-k="gpu">${mib(st.gpu.total)} of ${mib(st.gpu.budget)}</dd>` +
    (st.reason ? `<dt>note</dt><dd data-k="reason">${escapeHtml(st.reason)}</dd>` : '') +
    `</dl>`;
}
