// Time series (issue 47, headless): OME-Zarr stores with a t axis written
// by ngff-zarr (tests/fixtures/time-series-stores.py: t = 8, a moving and
// growing ball plus noise, 128^3, uint8 and float32, chunks of 1 and of 4
// time points, one sharded), read with `extract STORE --time SLICE`. Truth
// from outside: at each time point selected, zfpy's decode of NumPy's array
// of that time point at the store's rate (the record's: chosen from the data
// at the first time point, kept for the rest), marched by vtkFlyingEdges3D,
// gives our triangles exactly and our area within 1e-5 (the store path
// encodes each 64^3 brick on its own; zfp codes 4^3 blocks independently, so
// that is the whole volume's decode). vtkMarchingCubes gives as many less
// the degenerate triangles it drops (lossless-chunk-reference.test.ts says
// why). The slice is resolved by Python's rule (checked against Python), and
// a bad or empty selection is refused naming the store.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { repoRoot, runPython } from '../../helpers/python.ts';
import { cli } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'time-series-'));
interface Manifest {
  t: number;
  n: number;
  timeStep: number;
  timeUnit: string;
  /** The uint8 series as one raw file per time point (a pattern). */
  steps: string;
  stores: Record<string, { store: string; raw: string; dtype: string; timePerChunk: number; sharded: boolean }>;
}
let manifest: Manifest;

beforeAll(() => {
  const out = execFileSync(join(repoRoot, '.venv-converter/bin/python'), [join(repoRoot, 'tests/fixtures/time-series-stores.py'), work], {
    encoding: 'utf8',
    timeout: 300_000,
    stdio: ['ignore', 'pipe', 'ignore'],
  });
  manifest = JSON.parse(out);
}, 300_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

interface Reference {
  time: number;
  iso: number;
  flyingEdges: number;
  marchingCubes: number;
  degenerate: number;
  area: number;
}

/** Per time point and isovalue: VTK over zfpy's rate-R decode of NumPy's array of that time point. */
function reference(raw: string, dtype: string, rate: number, times: number[], isos: number[]): Reference[] {
  return JSON.parse(
    runPython(
      `
import sys, json, numpy as np, zfpy, vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
raw, dtype, n, T, rate = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5])
times, isos = json.loads(sys.argv[6]), json.loads(sys.argv[7])
series = np.fromfile(raw, dtype).reshape(T, n, n, n)
out = []
for t in times:
    v = np.ascontiguousarray(series[t].astype(np.float32))
    dec = zfpy.decompress_numpy(zfpy.compress_numpy(v, rate=rate, write_header=True))
    img = vtk.vtkImageData(); img.SetDimensions(n, n, n)
    img.GetPointData().SetScalars(numpy_to_vtk(dec.ravel(), deep=1))
    for iso in isos:
        iso = float(np.float32(iso))
        def march(cls):
            m = cls(); m.SetInputData(img); m.SetValue(0, iso); m.ComputeNormalsOff(); m.ComputeScalarsOff(); m.Update()
            return m.GetOutput()
        fe = march(vtk.vtkFlyingEdges3D)
        p = vtk_to_numpy(fe.GetPoints().GetData()).astype(np.float64)[vtk_to_numpy(fe.GetPolys().GetConnectivityArray()).reshape(-1, 3)]
        area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        degenerate = (p[:, 0] == p[:, 1]).all(1) | (p[:, 1] == p[:, 2]).all(1) | (p[:, 0] == p[:, 2]).all(1)
        out.append({'time': t, 'iso': iso, 'flyingEdges': fe.GetNumberOfPolys(), 'marchingCubes': march(vtk.vtkMarchingCubes).GetNumberOfPolys(),
                    'degenerate': int(degenerate.sum()), 'area': float(area.sum())})
print(json.dumps(out))
`,
      [raw, dtype, String(manifest.n), String(manifest.t), String(rate), JSON.stringify(times), JSON.stringify(isos)],
    ),
  );
}

/** Python's own selection: range(*slice(start, stop, step).indices(count)). */
function pythonSlice(slices: (number | null)[][], count: number): number[][] {
  return JSON.parse(
    runPython('import sys, json\nprint(json.dumps([list(range(*slice(*s).indices(int(sys.argv[2])))) for s in json.loads(sys.argv[1])]))', [
      JSON.stringify(slices),
      String(count),
    ]),
  );
}

interface SeriesRecord {
  rate: number;
  time: { selection: string; count: number; indices: number[]; unit?: string };
  isosurfaces: {
    iso: number;
    time: number;
    timeValue?: number;
    timeUnit?: string;
    triangles: number;
    area: number;
    bytesFetched: number;
    msToSurface: number;
    ply?: string;
    error?: string;
  }[];
  timePoints: { time: number; rate: number; gpuBytesAfter: number; store: { source: { time: { index: number; count: number } } } }[];
}

const ISOS = [60, 120];

describe('extract STORE --time SLICE: each time point of a series written by ngff-zarr against zfpy + VTK', () => {
  // uint8 and float32; chunks of 1 and of 4 time points (the float32 one sharded); whole series, and slices across chunks of 4
  const cases: [string, string, number[]][] = [
    ['ball_uint8_t1.ome.zarr', '0:8', [0, 1, 2, 3, 4, 5, 6, 7]],
    ['ball_float32_t4.ome.zarr', '0:8', [0, 1, 2, 3, 4, 5, 6, 7]],
    ['ball_uint8_t4.ome.zarr', '-7::3', [1, 4, 7]],
    ['ball_float32_t1.ome.zarr', '::-3', [7, 4, 1]],
  ];
  for (const [name, selection, times] of cases) {
    it(`${name} --time ${selection}: time points ${times.join(', ')}, ${ISOS.length} isovalues each`, () => {
      const entry = manifest.stores[name];
      const json = join(work, `${name}.json`);
      const prefix = join(work, name.replace(/\W/g, '_'));
      // --time=SLICE: a slice that starts with '-' would read as an option
      const r = cli('extract', entry.store, '--iso', ISOS.join(','), `--time=${selection}`, '--ply', prefix, '--json', json);
      expect(r.status, r.stderr).toBe(0);
      const record: SeriesRecord = JSON.parse(readFileSync(json, 'utf8'));
      expect(record.time).toEqual({ selection, count: manifest.t, indices: times, unit: manifest.timeUnit });
      // one decode: every time point at the rate chosen at the first
      expect(record.timePoints.map((p) => p.rate)).toEqual(times.map(() => record.rate));
      expect(record.timePoints.map((p) => p.store.source.time)).toEqual(times.map((t) => ({ index: t, count: manifest.t })));
      // each time point's session and surfaces gave back every GPU byte before the next opened
      expect(record.timePoints.map((p) => p.gpuBytesAfter)).toEqual(times.map(() => 0));
      const ref = reference(entry.raw, entry.dtype, record.rate, times, ISOS);
      expect(record.isosurfaces.map((s) => [s.time, s.iso])).toEqual(ref.map((x) => [x.time, x.iso]));
      const rows = record.isosurfaces.map((s, i) => ({ ...ref[i], ours: s.triangles, oursArea: s.area }));
      console.log(
        `${name} at rate ${record.rate}:\n` +
          rows
            .map(
              (x) =>
                `  t ${x.time} iso ${x.iso}: ours ${x.ours}, vtkFlyingEdges3D ${x.flyingEdges}, vtkMarchingCubes ${x.marchingCubes} (${x.degenerate} degenerate); area ${x.oursArea.toFixed(2)} / ${x.area.toFixed(2)}`,
            )
            .join('\n'),
      );
      for (const [i, s] of record.isosurfaces.entries()) {
        const x = ref[i];
        const where = `t ${s.time} iso ${s.iso}`;
        expect(s.error, where).toBeUndefined();
        expect(s.triangles, where).toBe(x.flyingEdges);
        expect(x.marchingCubes, where).toBe(x.flyingEdges - x.degenerate);
        expect(Math.abs(s.area - x.area) / x.area, where).toBeLessThan(1e-5);
        expect(s.timeValue, where).toBe(s.time * manifest.timeStep);
        expect(s.timeUnit, where).toBe(manifest.timeUnit);
        expect(s.bytesFetched, where).toBeGreaterThan(0);
        expect(s.msToSurface, where).toBeGreaterThan(0);
        expect(s.ply, where).toBe(`${prefix}-t${s.time}-iso${s.iso}.ply`);
        expect(existsSync(s.ply!), where).toBe(true);
      }
      // the ball grows: more surface at each later time point
      const at120 = rows.filter((x) => x.iso === 120).sort((a, b) => a.time - b.time);
      for (let i = 1; i < at120.length; i++) expect(at120[i].ours).toBeGreaterThan(at120[i - 1].ours);
    }, 300_000);
  }

  it("a store the converter made from one file per time point (convert 'step_*.raw' --time): --time 0:8:3 against zfpy + VTK at its rate", () => {
    const out = join(work, 'converted.zarr');
    execFileSync(
      process.execPath,
      [
        join(repoRoot, 'scripts/convert.mjs'),
        manifest.steps,
        '--time',
        '--time-step',
        '0.5',
        '--time-unit',
        'second',
        '--rate',
        '8',
        '--out',
        out,
        '--quiet',
      ],
      { cwd: repoRoot, stdio: 'pipe', timeout: 600_000 },
    );
    const json = join(work, 'converted.json');
    const r = cli('extract', out, '--iso', ISOS.join(','), '--time', '0:8:3', '--json', json);
    expect(r.status, r.stderr).toBe(0);
    const record: SeriesRecord = JSON.parse(readFileSync(json, 'utf8'));
    // a zfp store: its chunks' rate, and per time point its range arrays
    expect(record.rate).toBe(8);
    expect(record.time).toEqual({ selection: '0:8:3', count: manifest.t, indices: [0, 3, 6], unit: 'second' });
    expect(record.timePoints.map((p) => p.gpuBytesAfter)).toEqual([0, 0, 0]);
    const ref = reference(manifest.stores['ball_uint8_t1.ome.zarr'].raw, 'uint8', 8, [0, 3, 6], ISOS);
    expect(record.isosurfaces.map((s) => [s.time, s.iso, s.triangles, s.timeValue])).toEqual(
      ref.map((x) => [x.time, x.iso, x.flyingEdges, x.time * 0.5]),
    );
    for (const [i, s] of record.isosurfaces.entries()) expect(Math.abs(s.area - ref[i].area) / ref[i].area).toBeLessThan(1e-5);
  }, 300_000);

  it('one time point (--time 5) as before: no time fields, the record of that time point', () => {
    const entry = manifest.stores['ball_uint8_t4.ome.zarr'];
    const json = join(work, 'one.json');
    const r = cli('extract', entry.store, '--iso', '120', '--time', '5', '--rate', '8', '--json', json);
    expect(r.status, r.stderr).toBe(0);
    const record = JSON.parse(readFileSync(json, 'utf8'));
    expect(record.time).toBeUndefined();
    expect(record.timePoints).toBeUndefined();
    expect(record.isosurfaces[0].time).toBeUndefined();
    expect(record.store.source.time).toEqual({ index: 5, count: 8 });
    expect(record.isosurfaces[0].triangles).toBe(reference(entry.raw, entry.dtype, 8, [5], [120])[0].flyingEdges);
  }, 300_000);

  it('refusals name the store and the count: an empty selection, a step of 0, not a slice, a file that is no store', () => {
    const entry = manifest.stores['ball_uint8_t1.ome.zarr'];
    const empty = cli('extract', entry.store, '--iso', '100', '--time', '8:20');
    expect(empty.status).toBe(2);
    expect(empty.stderr).toContain(`--time 8:20: ${entry.store} has 8 time points (0..7); the slice 8:20 selects none of them`);
    const zero = cli('extract', entry.store, '--iso', '100', '--time', '0:8:0');
    expect(zero.status).toBe(2);
    expect(zero.stderr).toContain('--time 0:8:0: the step is 0');
    const bad = cli('extract', entry.store, '--iso', '100', '--time', '1:x');
    expect(bad.status).toBe(2);
    expect(bad.stderr).toContain('--time 1:x: not a slice');
    const notStore = cli('extract', entry.raw, '--iso', '100', '--time', '0:2');
    expect(notStore.status).toBe(2);
    expect(notStore.stderr).toContain('--time is for a Zarr store');
    const missing = cli('extract', join(work, 'nothing.zarr'), '--iso', '100', '--time', '0:2');
    expect(missing.status).toBe(2);
  });
});

describe('the slice rule', () => {
  it("start:stop[:step] selects what Python's slice selects, negative and omitted parts included", async () => {
    const { parseTimeSlice, sliceIndices } = await import('../../../src/cli/time-selection.ts');
    const texts = [
      '0:8',
      ':',
      '::',
      '2:',
      ':3',
      '-3:',
      ':-3',
      '-7::3',
      '::-1',
      '::-3',
      '5:1:-2',
      '-1:-9:-1',
      '100:',
      '-100:100',
      '0:20:2',
      '3:3',
      '7:2',
      '1::2',
      '-2::-2',
    ];
    const parts = texts.map((t) => {
      const s = parseTimeSlice(t);
      if (typeof s === 'string') throw new Error(`${t}: ${s}`);
      return s;
    });
    for (const count of [0, 1, 8, 21]) {
      const python = pythonSlice(
        parts.map((s) => [s.start, s.stop, s.step]),
        count,
      );
      texts.forEach((t, i) => expect(sliceIndices(parts[i], count), `${t} of ${count}`).toEqual(python[i]));
    }
    expect(parseTimeSlice('0:8:0')).toMatch(/step is 0/);
    for (const bad of ['a:b', '1.5:3', '1:2:3:4', '1', '']) expect(typeof parseTimeSlice(bad), bad).toBe('string');
  });
});
