// `cli bench --draw rays|mesh` (issue 46): the harness draws one image after
// each surface (offscreen at the Fit view, as `render` draws it) and times it.
// On the fuel volume (64^3, rate 8 given, so no rate choice), one sequence of
// 3 isovalues each way: every record has a frame time > 0 and an image time of
// surface + frame, the summaries their means and medians; the surfaces are
// those of the plain bench (the harness draws, it does not change them):
// mesh: the same isovalues, active, new and occupied blocks and triangles;
// rays: the same isovalues, active and new blocks (the cache the rays read),
// and no triangles (the surfaces are cache-only, as render's).
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect, it } from 'vitest';
import type { BenchRecord, BenchSummary } from '../../../src/bench/harness.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'bench-draw-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

const VOLUME = join(sharedData, 'volumes', 'fuel_64x64x64_float32.raw');

interface Result {
  options: { draw?: string; size?: number[]; frameTiming?: string };
  records: BenchRecord[];
  summaries: BenchSummary[];
}

function bench(name: string, ...extra: string[]): { status: number | null; stderr: string; stdout: string; json?: Result } {
  const out = join(work, `${name}.json`);
  const r = spawnSync(
    process.execPath,
    [
      '--import',
      join(repoRoot, 'scripts/register-node-loaders.mjs'),
      join(repoRoot, 'src/cli/main.ts'),
      'bench',
      VOLUME,
      '--rate',
      '8',
      '--modes',
      'random',
      '--count',
      '3',
      '--seed',
      '5',
      '--json',
      out,
      ...extra,
    ],
    { encoding: 'utf8', timeout: 120_000 },
  );
  return {
    status: r.status,
    stderr: r.stderr,
    stdout: r.stdout,
    ...(r.status === 0 ? { json: JSON.parse(readFileSync(out, 'utf8')) as Result } : {}),
  };
}

const same = (r: BenchRecord, triangles: boolean) => ({
  mode: r.mode,
  index: r.index,
  iso: r.iso,
  activeBlocks: r.activeBlocks,
  newBlocks: r.newBlocks,
  ...(triangles ? { occupiedBlocks: r.occupiedBlocks, triangles: r.triangles } : {}),
});

describe('cli bench --draw', () => {
  it('rays and mesh: a frame time per surface, image = surface + frame, the surfaces of the plain bench', () => {
    const plain = bench('plain');
    expect(plain.status, plain.stderr).toBe(0);
    expect(plain.json!.records.every((r) => r.frameMs === undefined)).toBe(true);
    expect(plain.json!.summaries[0].meanFrameMs).toBeUndefined();
    expect(plain.json!.records.some((r) => r.triangles > 0)).toBe(true);
    for (const draw of ['rays', 'mesh'] as const) {
      const run = bench(draw, '--draw', draw, '--size', '96x72');
      expect(run.status, run.stderr).toBe(0);
      const { options, records, summaries } = run.json!;
      expect(options).toMatchObject({ draw, size: [96, 72] });
      expect(['timestamp-query', 'queue-wall-time']).toContain(options.frameTiming);
      expect(records).toHaveLength(3);
      for (const r of records) {
        expect(r.frameMs, `${draw} ${r.iso}`).toBeGreaterThan(0);
        expect(r.imageMs).toBeCloseTo(r.gpuMs + r.frameMs!, 9);
      }
      const s = summaries[0];
      for (const k of ['meanFrameMs', 'medianFrameMs', 'meanImageMs', 'medianImageMs'] as const) expect(s[k], k).toBeGreaterThan(0);
      // the table's frame and image columns
      expect(run.stdout).toContain(`${draw} frame ms`);
      expect(run.stdout).toContain('image ms');
      expect(records.map((r) => same(r, draw === 'mesh'))).toEqual(plain.json!.records.map((r) => same(r, draw === 'mesh')));
      if (draw === 'rays') expect(records.every((r) => r.triangles === 0)).toBe(true);
    }
  }, 150_000);

  it('usage: --draw takes rays or mesh; --size only with --draw', () => {
    expect(bench('bad-draw', '--draw', 'points').status).toBe(2);
    expect(bench('bad-size', '--size', '64x64').status).toBe(2);
  });
});
