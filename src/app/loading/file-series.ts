// Several volume files dropped (or picked) together as a time series (issue
// 47, "Series in"): when their names say so (numbered names, one kind of
// file: raw, NRRD, or 3-D TIFF stacks), or the user says so when the names
// leave it open (SeriesDialog), the files are checked against each other
// (src/volume/series-files.ts: a file of another shape or size refuses the
// set, by its name, before anything is opened) and open as a read-only Zarr
// store of T time points (src/store/zarr/file-series-store.ts) through the
// page's one store path (StoreView.openStore): playback, the budget and the
// link's t= as for any store with a t axis. Raw files take their shape and
// type from the first file's name, or the volume form asks once for the
// series. Anything else (single-page TIFF slices: a z stack; mixed or other
// kinds) goes on as before.
import type { AsyncReadable } from '@zarrita/storage';
import { isDType } from '../../core/dtype.ts';
import { parseVolumeName } from '../../core/naming.ts';
import { FileSeriesStore } from '../../store/zarr/file-series-store.ts';
import type { OpenRequest, VolumeFileFacts } from '../../volume/open-volume.ts';
import { nrrdSeries, rawSeries, SeriesError, type SeriesFiles, tiffPageCount, tiffSeries } from '../../volume/series-files.ts';
import { seriesKindOf, seriesLabel, seriesOrder } from '../../volume/series-names.ts';
import type { SeriesAnswer } from '../ui/series-dialog.ts';

export interface FileSeriesDeps {
  /** The volume form: a raw series' shape, type and rate, asked once (for the first file). */
  askShape(facts: VolumeFileFacts): Promise<OpenRequest | undefined>;
  /** Whether files whose names leave it open are a series. */
  askSeries(count: number, first: string, last: string, why: string): Promise<SeriesAnswer>;
  onError(message: string): void;
  onNotice(message: string): void;
  /** Opens the series' store (StoreView.openStore), at `rate` when the form gave one. */
  openStore(store: AsyncReadable, name: string, rate: number | undefined): Promise<void>;
}

/**
 * What became of a drop: opened (or being opened) as a series, refused or
 * cancelled (nothing more to do), or for the usual path: every file as
 * before (`files`: a TIFF z stack, mixed kinds) or the first file only.
 */
export type SeriesOutcome = { kind: 'series' | 'refused' | 'cancelled' | 'files' } | { kind: 'first'; file: File };

export class FileSeriesOpener {
  #gen = 0;

  constructor(private readonly d: FileSeriesDeps) {}

  /** A newer drop: what this one was checking or asking is dropped. */
  supersede(): void {
    this.#gen++;
  }

  async open(files: File[]): Promise<SeriesOutcome> {
    const gen = ++this.#gen;
    const stale = () => gen !== this.#gen;
    const is = (kind: 'series' | 'refused' | 'cancelled' | 'files'): SeriesOutcome => ({ kind: stale() ? 'cancelled' : kind });
    if (files.length < 2) return is('files');
    const kind = seriesKindOf(files.map((f) => f.name));
    if (!kind) return is('files');
    const order = seriesOrder(files.map((f) => f.name));
    const ordered = order.order.map((i) => files[i]);
    try {
      // single-page TIFF files are the slices of one z stack (the usual path); 3-D stacks may be a series
      if (kind === 'tiff' && (await tiffPageCount(ordered[0])) <= 1) return is('files');
      if (stale()) return is('cancelled');
      if (!order.sure) {
        const answer = await this.d.askSeries(
          ordered.length,
          ordered[0].name,
          ordered.at(-1)!.name,
          order.why ?? 'the names are not numbered',
        );
        if (stale() || answer === 'cancel') return is('cancelled');
        if (answer === 'first') return { kind: 'first', file: ordered[0] };
      }
      let rate: number | undefined;
      let series: SeriesFiles;
      if (kind === 'raw') {
        const named = parseVolumeName(ordered[0].name);
        let dims = named.dims;
        let dtype = named.dtype;
        if (!dims || !dtype) {
          const facts: VolumeFileFacts = {
            fileName: `${ordered[0].name} (the first of ${ordered.length} time points; the same for all)`,
            kind: 'raw',
            bytes: ordered[0].size,
            dims,
            dtype,
            missing: [...(dims ? [] : ['dims' as const]), ...(dtype ? [] : ['dtype' as const])],
            compresses: true,
          };
          const answer = await this.d.askShape(facts);
          if (stale() || !answer) return is('cancelled');
          dims = answer.dims;
          dtype = answer.dtype && isDType(answer.dtype) ? answer.dtype : dtype;
          rate = answer.rate;
          if (!dims || !dtype) return is('cancelled');
        }
        series = rawSeries(ordered, dims, dtype);
      } else {
        if (kind === 'tiff' && ordered.length > 4) this.d.onNotice(`Checking ${ordered.length} TIFF stacks…`);
        series = kind === 'nrrd' ? await nrrdSeries(ordered) : await tiffSeries(ordered);
      }
      if (stale()) return is('cancelled');
      const label = seriesLabel(series.names);
      await this.d.openStore(new FileSeriesStore(series, label), label, rate);
      return is('series');
    } catch (e) {
      if (stale()) return is('cancelled');
      // a SeriesError names the file; anything else is worded with the set
      const why = e instanceof SeriesError ? e.message : `${ordered[0].name} … ${ordered.at(-1)!.name}: ${(e as Error).message}`;
      this.d.onError(`Not opened as a time series: ${why}. The volume on screen stays.`);
      return is('refused');
    }
  }
}
