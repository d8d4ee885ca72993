// The fuzz runner tells outcomes apart: a suite that cannot fail proves nothing.
import { describe, expect, it } from 'vitest';
import { runTarget } from '../../fuzz/runner.ts';
import { makeCase } from '../../fuzz/mutators.ts';
import type { FuzzTarget } from '../../fuzz/target.ts';

class ReaderError extends Error {}

function target(open: FuzzTarget['open']): FuzzTarget {
  return {
    reader: 'test',
    seeds: async () => [{ name: 'seed_4x4x4_float32.raw', bytes: new Uint8Array(256) }],
    open,
    isCleanRejection: (e, name) => e instanceof ReaderError && e.message.includes(name),
  };
}

const opts = { casesPerReader: 3, runSeed: 1, timeLimitMs: 200, allocLimitBytes: 2 ** 30 };

describe('fuzz runner', () => {
  it('counts clean rejections, acceptances, crashes, hangs and absurd allocations', async () => {
    expect(
      (
        await runTarget(
          target(async (name) => {
            throw new ReaderError(`${name}: bad`);
          }),
          opts,
        )
      ).rejected,
    ).toBe(3);
    expect(
      (
        await runTarget(
          target(async () => 'ok'),
          opts,
        )
      ).accepted,
    ).toBe(3);
    // the reader's error without the file's name, and a bare TypeError, are crashes
    expect(
      (
        await runTarget(
          target(async () => {
            throw new ReaderError('bad');
          }),
          opts,
        )
      ).crashes,
    ).toBe(3);
    expect(
      (
        await runTarget(
          target(async () => {
            throw new TypeError('x is undefined');
          }),
          opts,
        )
      ).crashes,
    ).toBe(3);
    expect(
      (
        await runTarget(
          target(() => new Promise(() => {})),
          opts,
        )
      ).hangs,
    ).toBe(3);
    const alloc = await runTarget(
      target(async () => new Float64Array(2 ** 28)),
      opts,
    );
    expect(alloc.allocs).toBe(3);
    expect(alloc.problems[0].message).toMatch(/new Float64Array\(268435456\) of 2147483648 bytes requested \(limit 1073741824\)/);
    // memory that does not pass through the guarded constructors (Buffer, engine allocations): seen by sampling
    const grown = await runTarget(
      target(async () => {
        const b = Buffer.alloc(100 << 20, 1);
        await new Promise((r) => setTimeout(r, 60));
        return b.length;
      }),
      { ...opts, allocLimitBytes: 64 << 20, casesPerReader: 1, timeLimitMs: 10_000 },
    );
    expect(grown.allocs, JSON.stringify(grown)).toBe(1);
    expect(grown.problems[0].message).toMatch(/the process grew by \d+ bytes during the case \(limit 67108864\)/);
    // the guard is gone after the run
    expect(new Float64Array(4).length).toBe(4);
  });

  it('makes the same cases from the same seeds', () => {
    const seeds = [{ name: 'a_4x4x4_float32.raw', bytes: Uint8Array.from({ length: 256 }, (_, i) => i) }];
    for (let i = 0; i < 50; i++) {
      const a = makeCase(seeds, i, 7, 'raw');
      const b = makeCase(seeds, i, 7, 'raw');
      expect(a.name).toBe(b.name);
      expect(a.mutation).toBe(b.mutation);
      expect(Buffer.from(a.bytes).equals(Buffer.from(b.bytes))).toBe(true);
    }
  });
});
