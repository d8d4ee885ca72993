// Wires the store view into the page: a progress line over the view, a
// "Store" section at the top of the panel, the loader's install path, and
// window.zfpisoStore for the page tests.
import { fileZipBytes, isZipStoreName, ZipStore } from '../../store/zarr/zip-store.ts';
import { droppedFolder, pickDirectory, pickedFolder } from './folder.ts';
import { StoreView, type StorePageState, type StoreViewDeps } from './store-view.ts';

export function storeParameter(): string | null {
  return new URLSearchParams(location.search).get('store');
}

/** `?prefetch=MiB`: CPU bytes a series' next time point may take when fetched ahead (0: none); undefined: the default. */
export function prefetchParameter(): number | undefined {
  const v = new URLSearchParams(location.search).get('prefetch');
  const n = v === null || v.trim() === '' ? Number.NaN : Number(v);
  return Number.isFinite(n) && n >= 0 ? n * 2 ** 20 : undefined;
}

/** `?store=URL&ranges=URL`: per-brick ranges of a store of lossless chunks, written apart (convert --ranges-only). */
export function rangesParameter(): string | null {
  return new URLSearchParams(location.search).get('ranges');
}

/** The page's side of the store view; mount adds the progress line, the panel and window.zfpisoStore. */
export function mountStoreView(p: Omit<StoreViewDeps, 'publish' | 'line' | 'panel'>): StoreView {
  const line = document.createElement('div');
  line.id = 'store-progress';
  line.setAttribute('role', 'status');
  line.hidden = true;
  line.style.cssText =
    'position:absolute;left:8px;bottom:8px;padding:2px 8px;background:rgba(0,0,0,.6);color:#fff;font:12px system-ui;border-radius:4px;z-index:5';
  (document.getElementById('stage') ?? document.body).append(line);
  const panel = document.createElement('section');
  panel.id = 'store-section';
  panel.hidden = true;
  const aside = document.getElementById('panel');
  aside?.insertBefore(panel, aside.querySelector('#volume-section'));
  const w = window as unknown as { zfpisoStore?: StorePageState };
  const view = new StoreView({
    ...p,
    publish: (s) => {
      w.zfpisoStore = s;
    },
    line,
    panel,
  });
  const openFolder = (f: { name: string; store: Parameters<StoreView['openStore']>[0] } | null) => {
    if (f) void view.openStore(f.store, f.name);
  };
  // A zipped store (.ozx, .zip) dropped or picked as a file opens as a store, read in place
  const zipOf = (files: FileList | null | undefined): File | null =>
    files && files.length === 1 && isZipStoreName(files[0].name) ? files[0] : null;
  const openZip = (file: File) => void view.openStore(new ZipStore(fileZipBytes(file), file.name), file.name);
  window.addEventListener(
    'change',
    (e) => {
      const input = e.target as HTMLInputElement | null;
      const zip = input?.id === 'file-input' ? zipOf(input.files) : null;
      if (!zip) return;
      e.stopImmediatePropagation();
      input!.value = '';
      openZip(zip);
    },
    { capture: true },
  );
  // A dropped folder is a store (files keep going to the page's usual drop handler).
  window.addEventListener(
    'drop',
    (e) => {
      const zip = zipOf(e.dataTransfer?.files);
      if (zip) {
        e.preventDefault();
        e.stopImmediatePropagation();
        const overlay = document.getElementById('drop-overlay');
        if (overlay) overlay.hidden = true;
        window.dispatchEvent(new Event('dragleave'));
        openZip(zip);
        return;
      }
      const folder = droppedFolder(e);
      if (!folder) return;
      e.preventDefault();
      e.stopImmediatePropagation();
      const overlay = document.getElementById('drop-overlay');
      if (overlay) overlay.hidden = true;
      window.dispatchEvent(new Event('dragleave'));
      folder.then(openFolder, (err: Error) => p.onError(`Could not read the dropped folder: ${err.message}`));
    },
    { capture: true },
  );
  // "Open a .zarr folder…", next to the file picker
  const input = document.createElement('input');
  input.type = 'file';
  input.hidden = true;
  input.setAttribute('webkitdirectory', '');
  input.addEventListener('change', () => {
    openFolder(pickedFolder([...(input.files ?? [])]));
    input.value = '';
  });
  const button = document.createElement('button');
  button.type = 'button';
  button.id = 'open-store-folder';
  button.textContent = 'Open a .zarr folder…';
  button.addEventListener('click', () => {
    pickDirectory().then(
      (f) => (f ? openFolder(f) : input.click()),
      (err: Error) => {
        if (err.name !== 'AbortError') p.onError(err.message);
      },
    );
  });
  const fileInput = document.getElementById('file-input');
  fileInput?.parentElement?.append(button, input);
  return view;
}
