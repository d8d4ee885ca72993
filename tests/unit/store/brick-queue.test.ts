// A brick worker's queue (src/store/decode/brick-queue.ts), the part of the
// page's decode workers that decides what is read: a few reads at a time in
// the order asked, a read cancelled before it starts never runs (nothing is
// fetched or decoded for it) and is answered as aborted at once, a running
// one sees its signal abort; what the queue holds is bounded by what is
// asked for and not cancelled. Checked with a scripted reader: which reads
// ran, in which order, and every reply.
import { describe, expect, it } from 'vitest';
import type { BrickReply, BrickRequest } from '../../../src/store/decode/brick-protocol.ts';
import { BrickQueue } from '../../../src/store/decode/brick-queue.ts';

const idle = () => ({ bytes: 0, requests: 0, retries: 0, failed: 0 });
const request = (id: number): BrickRequest => ({ type: 'read', id, level: 0, brick: id });

function setup(concurrency = 2) {
  const started: number[] = [];
  const signals = new Map<number, AbortSignal>();
  const finish = new Map<number, () => void>();
  const replies: BrickReply[] = [];
  const queue = new BrickQueue(
    (r, signal) => {
      started.push(r.id);
      signals.set(r.id, signal);
      return new Promise((resolve) => {
        const done = () =>
          resolve({
            reply: signal.aborted
              ? { type: 'fail', id: r.id, error: { name: 'AbortError', kind: 'aborted', message: 'no longer needed' }, meter: idle() }
              : {
                  type: 'done',
                  id: r.id,
                  bytes: new Uint8Array(4),
                  range: [0, 1],
                  decode: { chunksDecoded: 1, bytesDecoded: 4, decodeMs: 0, nonFinite: 0 },
                  meter: idle(),
                },
            transfer: [],
          });
        finish.set(r.id, done);
        signal.addEventListener('abort', done, { once: true });
      });
    },
    (m) => replies.push(m),
    idle,
    concurrency,
  );
  return { queue, started, signals, finish, replies };
}
const settle = () => new Promise((r) => setTimeout(r, 0));

describe('BrickQueue', () => {
  it('runs at most `concurrency` reads, in the order asked; the next starts when one ends', async () => {
    const { queue, started, finish, replies } = setup(2);
    for (let id = 1; id <= 5; id++) queue.read(request(id));
    expect(started).toEqual([1, 2]);
    expect(queue.report).toEqual({ held: 5, maxHeld: 5 });
    finish.get(1)!();
    await settle();
    expect(started).toEqual([1, 2, 3]);
    expect(replies.map((r) => [r.type, r.id, r.queue?.held])).toEqual([['done', 1, 4]]);
  });

  it('a read cancelled before it starts never runs and is answered as aborted at once; one running sees its signal abort', async () => {
    const { queue, started, signals, finish, replies } = setup(1);
    for (let id = 1; id <= 4; id++) queue.read(request(id));
    queue.cancel(3);
    expect(replies.map((r) => [r.type, r.id])).toEqual([['fail', 3]]);
    expect((replies[0] as { error: { name: string } }).error.name).toBe('AbortError');
    expect(queue.report.held).toBe(3);
    queue.cancel(1);
    expect(signals.get(1)!.aborted).toBe(true);
    await settle();
    expect(replies.map((r) => [r.type, r.id])).toEqual([
      ['fail', 3],
      ['fail', 1],
    ]);
    finish.get(2)!();
    await settle();
    finish.get(4)!();
    await settle();
    // 3 never ran: nothing was fetched or decoded for it
    expect(started).toEqual([1, 2, 4]);
    expect(queue.report.held).toBe(0);
    // a cancel for a read already answered, or never asked for, changes nothing
    queue.cancel(2);
    queue.cancel(99);
    expect(replies.length).toBe(4);
  });

  it('newest wins, as the page asks: 8 reads, all cancelled and 8 others asked, 20 times over: the queue holds at most 8 and those running', async () => {
    const { queue, replies } = setup(3);
    let id = 0;
    let live: number[] = [];
    for (let round = 0; round < 20; round++) {
      for (const old of live) queue.cancel(old);
      live = Array.from({ length: 8 }, () => ++id);
      for (const r of live) queue.read(request(r));
      await settle();
    }
    expect(queue.report.maxHeld).toBeLessThanOrEqual(8 + 3);
    expect(replies.filter((r) => r.type === 'fail').length).toBe(8 * 19);
  });
});
