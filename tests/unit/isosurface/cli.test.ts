// `cli extract` and `cli bench` end to end: extract on a raw volume
// (compressed at a lossless rate on load) matches vtkMarchingCubes' figures
// from mc.json and writes readable PLY soups; bench writes deterministic
// records (two runs with one seed agree on every count) and summaries;
// a surface over the memory budget is recorded and makes extract exit 1;
// a wrong command line exits with code 2, a file that is not a volume with 1.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { repoRoot, runPython, sharedData } from '../../helpers/python.ts';
import { loadMcReference } from '../mc/reference.ts';

function cli(...args: string[]) {
  const r = spawnSync(
    process.execPath,
    ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
    {
      encoding: 'utf8',
      timeout: 240_000,
    },
  );
  return { status: r.status, stderr: r.stderr, stdout: r.stdout };
}

describe('isosurface CLI', () => {
  const dir = mkdtempSync(join(tmpdir(), 'iso-cli-'));
  const file = 'volumes/neghip_66x66x66_uint8.raw';
  const reference = loadMcReference().volumes.find((v) => v.file === file)!;

  it('extract: VTK figures, kept cache, PLY files', () => {
    const isos = reference.isosurfaces.map((s) => s.iso_nominal);
    const out = join(dir, 'extract.json');
    const r = cli(
      'extract',
      join(sharedData, file),
      '--iso',
      [...isos, isos[isos.length - 1]].join(','),
      '--rate',
      '20',
      '--ply',
      join(dir, 'neghip'),
      '--json',
      out,
    );
    expect(r.status, r.stderr).toBe(0);
    const result = JSON.parse(readFileSync(out, 'utf8'));
    expect(result.dims).toEqual([66, 66, 66]);
    expect(result.isosurfaces).toHaveLength(isos.length + 1);
    reference.isosurfaces.forEach((s, i) => {
      const rec = result.isosurfaces[i];
      const vtk = s.vtkMarchingCubes;
      expect(rec.iso).toBe(s.iso);
      expect(rec.triangles).toBe(vtk.triangles);
      expect(rec.vertices).toBe(vtk.points);
      expect(rec.indices).toBe(3 * vtk.triangles);
      expect(Math.abs(rec.surfaceArea - vtk.area) / vtk.area).toBeLessThan(0.005);
      for (let a = 0; a < 3; a++) {
        expect(Math.abs(rec.bbox.min[a] - vtk.bbox!.min[a])).toBeLessThanOrEqual(1);
        expect(Math.abs(rec.bbox.max[a] - vtk.bbox!.max[a])).toBeLessThanOrEqual(1);
      }
      expect(rec.hitRate).toBeCloseTo(1 - rec.newBlocks / rec.activeBlocks, 12);
      expect(rec.gpuMs).toBeGreaterThan(0);
    });
    // the repeated last isovalue finds all its blocks in the cache
    const again = result.isosurfaces[isos.length];
    expect(again.triangles).toBe(result.isosurfaces[isos.length - 1].triangles);
    expect(again.newBlocks).toBe(0);
    expect(again.hitRate).toBe(1);
    // PLY: numpy reads the mesh back, same triangle count and area
    const ply = result.isosurfaces[1].ply;
    const read = runPython(
      `
import sys, numpy as np, json
data = open(sys.argv[1], 'rb').read()
end = data.index(b'end_header\\n') + len(b'end_header\\n')
head = data[:end].decode()
nv = int(head.split('element vertex ')[1].split()[0]); nf = int(head.split('element face ')[1].split()[0])
v = np.frombuffer(data, '<f4', 3 * nv, end).reshape(-1, 3).astype(np.float64)
f = np.frombuffer(data[end + 12 * nv:], np.dtype([('n', 'u1'), ('i', '<i4', 3)]))
assert (f['n'] == 3).all()
t = v[f['i']]
area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
print(json.dumps({'faces': nf, 'vertices': nv, 'area': area}))
`,
      [ply],
    );
    const plyStats = JSON.parse(read);
    expect(plyStats.faces).toBe(result.isosurfaces[1].triangles);
    // the GPU's welded vertices as they are: VTK's merged points
    expect(plyStats.vertices).toBe(reference.isosurfaces[1].vtkMarchingCubes.points);
    expect(plyStats.area).toBeCloseTo(result.isosurfaces[1].surfaceArea, 3);
  });

  it('extract: surfaces over the memory budget are recorded with the message, and the exit status is 1', () => {
    const out = join(dir, 'budget.json');
    // 1.75 MB holds the small surface at 120.5, not the one at 20.5 (2828 active blocks); 120.5 again still fits.
    const r = cli('extract', join(sharedData, file), '--iso', '120.5,20.5,120.5', '--cache-budget', '1.75', '--json', out);
    expect(r.status, r.stderr).toBe(1);
    const result = JSON.parse(readFileSync(out, 'utf8'));
    expect(result.memoryBudgetBytes).toBe(1.75 * 2 ** 20);
    const [ok, failed, again] = result.isosurfaces;
    expect(ok.triangles).toBeGreaterThan(0);
    expect(failed).toEqual({
      iso: 20.5,
      error: expect.stringMatching(/^the surface at iso 20\.5 needs [\d.]+ MB .*the budget is 1\.75 MB/),
      overBudget: true,
    });
    expect(again.triangles).toBe(ok.triangles);
    expect(r.stderr).toContain(`error: ${failed.error}`);
    expect(r.stderr).toMatch(
      /error: 1 of 3 isosurfaces failed: 1 did not fit the GPU memory budget of 1\.75 MB \(iso 20\.5\); raise it with --cache-budget MB/,
    );
  });

  it('bench: records and summaries, the same counts for the same seed', () => {
    const zfp = join(sharedData, 'volumes/hydrogen_atom_128x128x128_float32.rate8.zfp');
    const args = ['bench', zfp, '--modes', 'random,sweep-down', '--count', '6', '--seed', '11', '--range', '10,120'];
    const runs = [join(dir, 'b1.json'), join(dir, 'b2.json')].map((out) => {
      const r = cli(...args, '--json', out);
      expect(r.status, r.stderr).toBe(0);
      expect(r.stdout).toMatch(/mode\s+surfaces\s+mean ms/);
      return JSON.parse(readFileSync(out, 'utf8'));
    });
    const [a, b] = runs;
    expect(Object.keys(a)).toEqual(['volume', 'adapter', 'options', 'rate', 'rateError', 'records', 'summaries']);
    expect(a.options).toMatchObject({ modes: ['random', 'sweep-down'], count: 6, seed: 11, range: [10, 120] });
    expect(a.records).toHaveLength(12);
    expect(a.summaries.map((s: { mode: string; count: number }) => [s.mode, s.count])).toEqual([
      ['random', 5],
      ['sweep-down', 5],
    ]);
    const counts = (run: typeof a) =>
      run.records.map((r: Record<string, number | string>) =>
        [r.mode, r.iso, r.activeBlocks, r.newBlocks, r.occupiedBlocks, r.triangles, r.cacheSlots].join(),
      );
    expect(counts(a)).toEqual(counts(b));
    // each mode starts cold
    for (const mode of ['random', 'sweep-down']) {
      const first = a.records.find((r: { mode: string; index: number }) => r.mode === mode && r.index === 0);
      expect(first.newBlocks).toBe(first.activeBlocks);
      expect(first.discarded).toBe(true);
    }
  });

  it('a wrong command line: exit code 2 and the usage; a file that is not a volume: 1', () => {
    const raw = join(sharedData, file);
    expect(cli('extract', raw).status).toBe(2);
    const bad = cli('extract', raw, '--iso', '1,x');
    expect(bad.status).toBe(2);
    expect(bad.stderr).toMatch(/--iso must be comma-separated numbers/);
    const noShape = cli('extract', join(sharedData, 'las/laspy_simple.las'), '--iso', '1');
    expect(noShape.status).toBe(1);
    expect(noShape.stderr).not.toMatch(/usage:/);
    expect(noShape.stderr).toMatch(/not a volume this command reads/);
    expect(cli('bench', raw, '--modes', 'zigzag').status).toBe(2);
  });
});
