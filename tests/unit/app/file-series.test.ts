// Issue 47, "Series in": what the page does with several dropped files
// (src/app/loading/file-series.ts), with the dialogs and the store view
// scripted: numbered names open as a series without asking; names that leave
// it open ask (series / first only / cancel); a raw series without a shape
// in its names asks the form once; a mismatched set is refused naming the
// file and opens nothing; single-page TIFF slices and mixed kinds go on as
// before; a newer drop wins.
import { describe, expect, it } from 'vitest';
import { FileSeriesOpener, type FileSeriesDeps } from '../../../src/app/loading/file-series.ts';
import { FileSeriesStore } from '../../../src/store/zarr/file-series-store.ts';
import type { SeriesAnswer } from '../../../src/app/ui/series-dialog.ts';

const raw = (name: string, bytes: number) => new File([new Uint8Array(bytes)], name);

function scripted(
  answers: { series?: SeriesAnswer; shape?: { dims: [number, number, number]; dtype: 'uint8' | 'uint16'; rate?: number } } = {},
) {
  const log = {
    asked: [] as string[],
    shapes: [] as string[],
    errors: [] as string[],
    opened: [] as { name: string; store: unknown; rate?: number }[],
  };
  const deps: FileSeriesDeps = {
    askShape: async (facts) => {
      log.shapes.push(facts.fileName);
      return answers.shape;
    },
    askSeries: async (n, first, last, why) => {
      log.asked.push(`${n} ${first}..${last}: ${why}`);
      return answers.series ?? 'cancel';
    },
    onError: (m) => log.errors.push(m),
    onNotice: () => {},
    openStore: async (store, name, rate) => {
      log.opened.push({ name, store, rate });
    },
  };
  return { opener: new FileSeriesOpener(deps), log };
}

describe('dropped files as a time series', () => {
  it('numbered names with the shape open as a series, in numeric order, without asking', async () => {
    const { opener, log } = scripted();
    const files = [10, 9, 8].map((t) => raw(`s_${t}_4x4x4_uint8.raw`, 64));
    expect(await opener.open(files)).toEqual({ kind: 'series' });
    expect(log.asked).toEqual([]);
    expect(log.opened.map((o) => o.name)).toEqual(['s_8_4x4x4_uint8.raw … s_10_4x4x4_uint8.raw (3 time points)']);
    const store = log.opened[0].store as FileSeriesStore;
    expect(store).toBeInstanceOf(FileSeriesStore);
    expect(store.series.names).toEqual(['s_8_4x4x4_uint8.raw', 's_9_4x4x4_uint8.raw', 's_10_4x4x4_uint8.raw']);
  });

  it('names that leave it open ask: series, first only, cancel', async () => {
    const files = [raw('b_4x4x4_uint8.raw', 64), raw('a_4x4x4_uint8.raw', 64)];
    const yes = scripted({ series: 'series' });
    expect(await yes.opener.open(files)).toEqual({ kind: 'series' });
    expect(yes.log.asked).toEqual([
      '2 a_4x4x4_uint8.raw..b_4x4x4_uint8.raw: the names are not numbered alike (no one number that counts the files)',
    ]);
    const first = scripted({ series: 'first' });
    expect(await first.opener.open(files)).toEqual({ kind: 'first', file: files[1] });
    expect(first.log.opened).toEqual([]);
    const cancel = scripted({ series: 'cancel' });
    expect(await cancel.opener.open(files)).toEqual({ kind: 'cancelled' });
    expect(cancel.log.opened).toEqual([]);
  });

  it('a raw series without a shape in its names asks the form once, for the first file, and takes its rate', async () => {
    const { opener, log } = scripted({ shape: { dims: [4, 4, 2], dtype: 'uint16', rate: 6 } });
    expect(await opener.open([raw('t2.raw', 64), raw('t1.raw', 64)])).toEqual({ kind: 'series' });
    expect(log.shapes).toEqual(['t1.raw (the first of 2 time points; the same for all)']);
    expect(log.opened[0].rate).toBe(6);
    expect((log.opened[0].store as FileSeriesStore).series.dtype).toBe('uint16');
    // the form cancelled: nothing opens
    const none = scripted();
    expect(await none.opener.open([raw('t2.raw', 64), raw('t1.raw', 64)])).toEqual({ kind: 'cancelled' });
  });

  it('a mismatched set is refused naming the file; nothing opens; the next drop opens', async () => {
    const { opener, log } = scripted();
    const files = [raw('v_0_4x4x4_uint8.raw', 64), raw('v_1_4x4x4_uint8.raw', 60), raw('v_2_4x4x4_uint8.raw', 64)];
    expect(await opener.open(files)).toEqual({ kind: 'refused' });
    expect(log.errors).toEqual([
      "Not opened as a time series: v_1_4x4x4_uint8.raw: 60 bytes; the series' shape 4×4×4 uint8 needs 64. The volume on screen stays.",
    ]);
    expect(log.opened).toEqual([]);
    expect(await opener.open([files[0], files[2]])).toEqual({ kind: 'series' });
  });

  it('mixed kinds, kinds a series is not made of and single files go on as before', async () => {
    const { opener } = scripted();
    expect(await opener.open([raw('a_1.raw', 1), raw('a_2.nrrd', 1)])).toEqual({ kind: 'files' });
    expect(await opener.open([raw('a_1.zfp', 1), raw('a_2.zfp', 1)])).toEqual({ kind: 'files' });
    expect(await opener.open([raw('a_1_4x4x4_uint8.raw', 64)])).toEqual({ kind: 'files' });
  });

  it('a newer drop wins over one still asking', async () => {
    let answer: (a: SeriesAnswer) => void = () => {};
    const { opener, log } = scripted();
    const deps = (opener as unknown as { d: FileSeriesDeps }).d;
    deps.askSeries = () => new Promise((r) => (answer = r));
    const pending = opener.open([raw('x.raw', 64), raw('y.raw', 64)]);
    await new Promise((r) => setTimeout(r, 0));
    opener.supersede();
    answer('series');
    expect(await pending).toEqual({ kind: 'cancelled' });
    expect(log.opened).toEqual([]);
  });
});
