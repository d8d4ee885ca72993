// The Store section of the panel: the levels (dims, chunks, bytes, what was
// fetched of each), the network (bytes, requests, in flight, aborted, cache
// hits, throughput, retries) and the GPU memory, counted where it is made
// (pools, per-level buffers, cache, vertices, against the budget).
// StorePageState is also what the page tests read (window.zfpisoStore).
import type { FetchCounters } from '../../store/fetch/chunk-fetcher.ts';
import type { ZfpStore } from '../../store/zarr/open-store.ts';
import type { PlaybackState } from './playback.ts';

/** A store of lossless chunks: the GPU rate of its bricks, the time point and channel shown. */
export interface StoreChoice {
  storeRate?: number;
  time?: number;
  channel?: number;
}

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
    /** Chunks the surface on screen reads at this level (drawn and ghosts: those its isovalue needs). */
    chunksShown: number;
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
  /**
   * GPU bytes (counted where they are made): this store's pools of compressed
   * chunks and surfaces (of which cache and vertices), all it holds
   * (`store`); against the page's one budget, what the page holds (`total`: a
   * store being replaced included) and the most it held since the budget was
   * last set (`peak`).
   */
  gpu: { pools: number; surfaces: number; cache: number; vertices: number; store: number; total: number; peak: number; budget: number };
  /** Where each piece of the step on screen is drawn: its level, scale (level-0 voxels per voxel) and origin (its own voxels). */
  parts: { level: number; scale: [number, number, number]; origin: [number, number, number] }[];
  /** The last steps shown (at most 64, oldest first): isovalue, triangles and welded vertices of all their levels. */
  steps: { iso: number; triangles: number; vertices: number }[];
  /** Steps shown since the store opened. */
  stepsShown: number;
  /** A store of lossless chunks: bricks in the decode workers now (asked for, not yet answered), and the most there were at once. */
  decodeQueue?: { queued: number; maxQueued: number };
  /** Chunks the surface needed by their ranges that the clip left out (never fetched). */
  clippedChunks?: number;
  /**
   * Refined by the view (null: level by level): the pixel tolerance, the
   * level tint, and per level the chunks on screen that hold surface
   * (`drawn`), the regions it covers (`regions`, with or without surface) and
   * its triangles; `final` when the view's whole cut is on screen.
   */
  cut: {
    tolerancePx: number;
    tint: boolean;
    levels: { level: number; drawn: number; regions: number; triangles: number }[];
    final: boolean;
  } | null;
  /**
   * The slider's value range and where it comes from: the store's metadata
   * or range arrays, or (provisional) the coarsest level read whole at open,
   * which finer levels may exceed.
   */
  valueRange?: { lo: number; hi: number; provisional: boolean; from: string };
  /** What the store is and how it is read (lossless chunks, the rate chosen, no range arrays, decode workers): information, not errors. */
  notes?: string[];
  /** A store with several time points: the time point on screen, the playback's state and its achieved rate (playback.ts). */
  playback?: PlaybackState;
}

/** The refinement controls' changes: by view or level by level, the pixel tolerance, the level tint. */
export interface CutChoice {
  cut?: boolean;
  tolerancePx?: number;
  tint?: boolean;
}

/** The refinement controls (made once per store and mode, so typing in them is not interrupted by the figures). */
function cutBlock(st: StorePageState, change: (next: CutChoice) => void): HTMLElement {
  const box = document.createElement('p');
  box.className = 'store-cut';
  const on = st.cut !== null;
  box.innerHTML =
    `<label title="each region at the level whose voxels project to at most the tolerance; the rest coarser"><input data-cut="cut" type="checkbox"${on ? ' checked' : ''}> refine by view</label> ` +
    (on
      ? `<label>tolerance <input data-cut="tolerancePx" type="number" min="0.25" max="64" step="0.25" value="${st.cut!.tolerancePx}"> px</label> ` +
        `<label><input data-cut="tint" type="checkbox"${st.cut!.tint ? ' checked' : ''}> tint by level</label>`
      : '');
  box.addEventListener('change', (e) => {
    const el = e.target as HTMLInputElement;
    const key = el.dataset.cut as keyof CutChoice | undefined;
    if (key === 'cut' || key === 'tint') change({ [key]: el.checked });
    else if (key === 'tolerancePx') {
      const v = Number(el.value);
      if (v >= 0.25 && v <= 64) change({ tolerancePx: v });
    }
  });
  return box;
}

const mib = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;
const escapeHtml = (s: string) => s.replace(/&/g, '&amp;').replace(/</g, '&lt;');

/**
 * A store of lossless chunks: what it is (format, codecs, type, chunks, how
 * bricks are made, the GPU rate, what float32 does to the values) and the
 * controls that reopen it another way (rate, channel; the time point: the
 * playback block, playback.ts). Made once per store (the figures below it
 * are redrawn on every change).
 */
function sourceBlock(store: ZfpStore, change: (next: StoreChoice) => void): HTMLElement | null {
  const src = store.source;
  if (!src) return null;
  const box = document.createElement('div');
  box.className = 'store-source';
  const select = (key: 'channel', label: string, v: { index: number; count: number }) =>
    v.count > 1
      ? `<label>${label} <select data-choice="${key}">${Array.from(
          { length: Math.min(v.count, 4096) },
          (_, i) => `<option value="${i}"${i === v.index ? ' selected' : ''}>${i}</option>`,
        ).join('')}</select> of ${v.count}</label>`
      : '';
  box.innerHTML =
    `<dl>` +
    `<dt>format</dt><dd data-k="format">${escapeHtml(src.format)}</dd>` +
    `<dt>codec</dt><dd data-k="codec">${escapeHtml(src.codecs.join(' + ') || 'none')}</dd>` +
    `<dt>type</dt><dd data-k="dtype">${escapeHtml(src.dtype)} (${escapeHtml(src.precision)} as float32)</dd>` +
    `<dt>chunks</dt><dd data-k="chunk-shape">${src.chunkShape.join('×')} (${escapeHtml(src.axes.join(''))}), read as ${escapeHtml(src.bricks)}</dd>` +
    `<dt>ranges</dt><dd data-k="ranges">${store.levels[0].rangesPath ? 'per brick, from the ranges sidecar' : "none: a level's first surface reads all of it (convert --ranges-only writes them; &amp;ranges=URL)"}</dd>` +
    `</dl>` +
    `<p class="store-choice"><label>GPU rate <input data-choice="storeRate" type="number" min="1" max="32" step="1" value="${src.rate}" title="zfp bits per value of the bricks compressed on the GPU"></label> ` +
    select('channel', 'channel', src.channel) +
    `</p>`;
  box.addEventListener('change', (e) => {
    const el = e.target as HTMLInputElement | HTMLSelectElement;
    const key = el.dataset.choice as keyof StoreChoice | undefined;
    const v = Number(el.value);
    if (!key || !Number.isFinite(v)) return;
    if (key === 'storeRate' && !(v >= 1 && v <= 32)) return;
    change({ [key]: v });
  });
  return box;
}

const sourceBlocks = new WeakMap<HTMLElement, { store: ZfpStore; figures: HTMLElement; cutOn: boolean; cut: HTMLElement }>();

export function renderStorePanel(
  panel: HTMLElement,
  store: ZfpStore,
  st: StorePageState,
  c: FetchCounters,
  change: (next: StoreChoice) => void = () => {},
  changeCut: (next: CutChoice) => void = () => {},
  playback: HTMLElement | null = null,
): void {
  let made = sourceBlocks.get(panel);
  if (!made || made.store !== store) {
    // the playback block stays (it outlives the store: each time point is a store opened again), first under the name
    for (const child of [...panel.children]) if (child !== playback) child.remove();
    if (playback && playback.parentElement !== panel) panel.prepend(playback);
    const figures = document.createElement('div');
    const block = sourceBlock(store, change);
    if (block) panel.append(block);
    const cut = cutBlock(st, changeCut);
    panel.append(cut, figures);
    made = { store, figures, cutOn: st.cut !== null, cut };
    sourceBlocks.set(panel, made);
  } else if (made.cutOn !== (st.cut !== null)) {
    const cut = cutBlock(st, changeCut);
    made.cut.replaceWith(cut);
    made.cut = cut;
    made.cutOn = st.cut !== null;
  }
  renderFigures(made.figures, panel, store, st, c);
}

function renderFigures(figures: HTMLElement, panel: HTMLElement, store: ZfpStore, st: StorePageState, c: FetchCounters): void {
  const cut = st.cut;
  const rows = st.levels
    .map((l) => {
      const on = cut?.levels[l.level];
      const shown = cut ? (on?.regions ?? 0) > 0 : st.shownLevel === l.level;
      const onScreen = cut ? `<td data-k="on-screen">${on?.drawn ?? 0}</td>` : '';
      return `<tr${shown ? ' class="shown"' : ''}><td>${l.level}</td><td>${l.dims.join('×')}</td><td>${l.chunksFetched} / ${l.chunks}</td>${onScreen}<td>${mib(l.storedBytes)}</td></tr>`;
    })
    .join('');
  panel.hidden = false;
  if (!panel.querySelector('h2')) {
    const head = document.createElement('div');
    head.innerHTML = `<h2>Store</h2><p class="store-name">${escapeHtml(store.name)}</p>`;
    panel.prepend(...head.childNodes);
  }
  figures.innerHTML =
    `<table class="store-levels"><thead><tr><th>level</th><th>dims</th><th>chunks fetched</th>${cut ? '<th title="chunks of the view\'s cut at this level that hold surface">on screen</th>' : ''}<th>${store.source ? 'values' : 'stored'}</th></tr></thead><tbody>${rows}</tbody></table>` +
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
    (st.gpu.total > st.gpu.store
      ? `<dt>GPU, store being replaced</dt><dd data-k="gpu-others">${mib(st.gpu.total - st.gpu.store)}</dd>`
      : '') +
    `<dt>GPU total</dt><dd data-k="gpu" title="everything the page streams holds on the GPU, against the budget; the most since the budget was set: ${mib(st.gpu.peak)}">${mib(st.gpu.total)} of ${mib(st.gpu.budget)}</dd>` +
    (st.valueRange
      ? `<dt>value range</dt><dd data-k="value-range" title="${escapeHtml(st.valueRange.from)}">${Number(st.valueRange.lo.toPrecision(6))} .. ${Number(st.valueRange.hi.toPrecision(6))}${st.valueRange.provisional ? ' (provisional: bricks not yet read may reach further)' : ''}</dd>`
      : '') +
    (st.notes?.length ? `<dt>about</dt><dd data-k="notes">${st.notes.map((n) => `<p>${escapeHtml(n)}</p>`).join('')}</dd>` : '') +
    (st.reason ? `<dt>note</dt><dd data-k="reason">${escapeHtml(st.reason)}</dd>` : '') +
    `</dl>`;
}
