// A `.zarr` folder from the user's disk as a store: dropped on the page
// (DataTransferItem.webkitGetAsEntry, read recursively) or picked (the File
// System Access API's directory picker where there is one, else an
// <input webkitdirectory>). Files are read only when zarrita asks for them.
import { DirectoryHandleStore, FileMapStore, type DirectoryHandleLike } from '../../store/zarr/stores.ts';
import type { AsyncReadable } from '@zarrita/storage';

interface Entry {
  isFile: boolean;
  isDirectory: boolean;
  name: string;
  fullPath: string;
}
interface FileEntry extends Entry {
  file(ok: (f: File) => void, fail: (e: unknown) => void): void;
}
interface DirEntry extends Entry {
  createReader(): { readEntries(ok: (e: Entry[]) => void, fail: (e: unknown) => void): void };
}

async function readAll(dir: DirEntry, prefix: string, out: Map<string, File>): Promise<void> {
  const reader = dir.createReader();
  for (;;) {
    const batch = await new Promise<Entry[]>((ok, fail) => reader.readEntries(ok, fail));
    if (batch.length === 0) return;
    for (const e of batch) {
      const path = prefix ? `${prefix}/${e.name}` : e.name;
      if (e.isDirectory) await readAll(e as DirEntry, path, out);
      else out.set(path, await new Promise<File>((ok, fail) => (e as FileEntry).file(ok, fail)));
    }
  }
}

/** The dropped directory, if the drop holds one: its name and a store over its files. */
export function droppedFolder(e: DragEvent): Promise<{ name: string; store: AsyncReadable }> | null {
  const items = [...(e.dataTransfer?.items ?? [])];
  const entry = items
    .map((i) => (i as unknown as { webkitGetAsEntry?(): Entry | null }).webkitGetAsEntry?.() ?? null)
    .find((x) => x?.isDirectory);
  if (!entry) return null;
  return (async () => {
    const files = new Map<string, File>();
    await readAll(entry as DirEntry, '', files);
    return { name: entry.name, store: new FileMapStore(files) };
  })();
}

/** Files picked with <input webkitdirectory>: paths start with the folder's name. */
export function pickedFolder(files: File[]): { name: string; store: AsyncReadable } | null {
  if (files.length === 0) return null;
  const name = files[0].webkitRelativePath.split('/')[0] || files[0].name;
  const map = new Map<string, File>();
  for (const f of files) map.set(f.webkitRelativePath.split('/').slice(1).join('/'), f);
  return { name, store: new FileMapStore(map) };
}

/** The directory picker (Chromium), or null where there is none. */
export async function pickDirectory(): Promise<{ name: string; store: AsyncReadable } | null> {
  const w = window as unknown as { showDirectoryPicker?: () => Promise<DirectoryHandleLike> };
  if (!w.showDirectoryPicker) return null;
  const handle = await w.showDirectoryPicker();
  return { name: handle.name, store: new DirectoryHandleStore(handle) };
}
