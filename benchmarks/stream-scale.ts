// The scaling half of bench:stream: generated stores of 512^3 ... N^3 voxels
// (the converter's gen: field, 64^3 chunks, rate 1, shards of 8^3 chunks,
// levels down to one chunk), each opened through HTTP on localhost and a
// simulated 100 Mbit/s link, within a 256 MB GPU budget: store bytes, the
// time to open (metadata), GPU bytes right after opening and after the first
// surface, the time to the first surface after the metadata, then for three
// narrow isovalues (near the field's maximum, as a scientist picks a
// feature) the finest level reached, the time to it, the chunks and bytes
// fetched for it, and the GPU bytes held. What matters: none of it should
// grow with the volume. Median of the repeats after a discarded first.
import { existsSync, readdirSync, statSync } from 'node:fs';
import { join } from 'node:path';
import type { GpuContext } from '../src/gpu/device.ts';
import { ChunkFetcher } from '../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu, createChunkStream } from '../src/store/gpu-port.ts';
import { HttpStore } from '../src/store/zarr/http-store.ts';
import { openStore } from '../src/store/zarr/open-store.ts';
import { MeteredStore, SimulatedLinkStore } from '../src/store/zarr/stores.ts';
import { summarize } from './lib/report.ts';

export const SCALE_ISOS = [2.5, 2.6, 2.7];
const MiB = 2 ** 20;

export function scaleStoreName(size: number): string {
  return `gen${size}-r1.zarr`;
}

/** Bytes of the files under a folder. */
function folderBytes(path: string): number {
  let total = 0;
  for (const e of readdirSync(path, { withFileTypes: true })) {
    const p = join(path, e.name);
    total += e.isDirectory() ? folderBytes(p) : statSync(p).size;
  }
  return total;
}

export interface ScaleRow {
  size: number;
  link: string;
  storeBytes: number;
  levels: number;
  openMs: number;
  gpuBytesAfterOpen: number;
  firstSurfaceMs: number;
  gpuBytesAfterFirst: number;
  surfaces: {
    iso: number;
    level: number;
    ms: number;
    level0Chunks: number;
    chunkBytes: number;
    triangles: number;
    gpuBytes: number;
    reason: string;
  }[];
}

export async function scaleRun(
  gpu: GpuContext,
  folder: string,
  baseUrl: string,
  sizes: number[],
  links: string[],
  repeats: number,
  budgetBytes: number,
): Promise<ScaleRow[]> {
  const rows: ScaleRow[] = [];
  for (const link of links) {
    for (const size of sizes) {
      const name = scaleStoreName(size);
      if (!existsSync(join(folder, name, 'zarr.json'))) throw new Error(`${name} is missing under ${folder}`);
      const storeBytes = folderBytes(join(folder, name));
      const runs: ScaleRow[] = [];
      for (let r = 0; r < repeats; r++) {
        const url = `${baseUrl}/${name}`;
        const metered = linkStore(url, link);
        const t0 = performance.now();
        const store = await openStore(metered, url);
        const fetcher = new ChunkFetcher(store);
        const port = chunkedGpu(gpu);
        const c = await createChunkStream(store, fetcher, port, budgetBytes);
        const t1 = performance.now();
        const gpuBytesAfterOpen = port.meter.bytes;
        let reason = '';
        c.onProgress((p) => {
          if (p.phase === 'stopped') reason = p.reason ?? '';
        });
        // the first surface: the coarsest level
        c.finest = c.coarsest;
        await c.setIsovalue(SCALE_ISOS[0]);
        const t2 = performance.now();
        const gpuBytesAfterFirst = port.meter.bytes;
        c.finest = 0;
        const surfaces: ScaleRow['surfaces'] = [];
        for (const iso of SCALE_ISOS) {
          const level0 = new Set<number>();
          let chunkBytes = 0;
          const off = fetcher.onChunk((level, chunk, bytes, fromCache) => {
            if (fromCache) return;
            chunkBytes += bytes.byteLength;
            if (level === 0) level0.add(chunk);
          });
          reason = '';
          const s0 = performance.now();
          await c.setIsovalue(iso);
          const ms = performance.now() - s0;
          off();
          surfaces.push({
            iso,
            level: c.shown?.level ?? -1,
            ms,
            level0Chunks: level0.size,
            chunkBytes,
            triangles: c.shown?.stats.triangles ?? 0,
            gpuBytes: port.meter.bytes,
            reason,
          });
        }
        c.destroy();
        runs.push({
          size,
          link,
          storeBytes,
          levels: store.levels.length,
          openMs: t1 - t0,
          gpuBytesAfterOpen,
          firstSurfaceMs: t2 - t1,
          gpuBytesAfterFirst,
          surfaces,
        });
        console.log(
          `${name}, ${link}, run ${r}: open ${(t1 - t0).toFixed(0)} ms, first surface ${(t2 - t1).toFixed(0)} ms after the metadata, ` +
            surfaces
              .map(
                (s) =>
                  `iso ${s.iso}: level ${s.level} in ${s.ms.toFixed(0)} ms, ${s.level0Chunks} level-0 chunks, ${s.triangles} triangles`,
              )
              .join('; '),
        );
      }
      // medians of the timed figures over the runs after the first; counts from the last run
      const kept = runs.length > 1 ? runs.slice(1) : runs;
      const last = runs[runs.length - 1];
      rows.push({
        ...last,
        openMs: summarize(kept.map((x) => x.openMs)).median,
        firstSurfaceMs: summarize(kept.map((x) => x.firstSurfaceMs)).median,
        surfaces: last.surfaces.map((s, i) => ({ ...s, ms: summarize(kept.map((x) => x.surfaces[i].ms)).median })),
      });
    }
  }
  return rows;
}

/** The rows as the table bench:stream prints. */
export function scaleTable(rows: ScaleRow[]): (string | number)[][] {
  const out: (string | number)[][] = [];
  for (const r of rows) {
    for (const s of r.surfaces) {
      out.push([
        `${r.size}^3`,
        r.link,
        (r.storeBytes / MiB).toFixed(0),
        r.levels,
        r.openMs,
        (r.gpuBytesAfterOpen / MiB).toFixed(2),
        r.firstSurfaceMs,
        (r.gpuBytesAfterFirst / MiB).toFixed(2),
        s.iso,
        s.level,
        s.ms,
        s.level0Chunks,
        (s.chunkBytes / MiB).toFixed(2),
        s.triangles,
        (s.gpuBytes / MiB).toFixed(1),
      ]);
    }
  }
  return out;
}

/** The store at `url` over localhost, or through the simulated link (100 Mbit/s, 20 ms per request), metered. */
export function linkStore(url: string, link: string): MeteredStore {
  const inner = new HttpStore(url);
  return new MeteredStore(link === 'localhost' ? inner : new SimulatedLinkStore(inner, { mbitPerSecond: 100, latencyMs: 20 }));
}

export const SCALE_HEADER = [
  'volume',
  'link',
  'store MiB',
  'levels',
  'open ms',
  'GPU MiB after open',
  'first surface ms (after metadata)',
  'GPU MiB after first',
  'iso',
  'level shown',
  'ms to it',
  'L0 chunks fetched',
  'MiB fetched',
  'triangles',
  'GPU MiB',
];
