// A brick worker's queue (brick-worker.ts): reads run a few at a time, in
// the order asked; a read cancelled before it starts is dropped without
// fetching or decoding anything (answered as aborted at once), one running
// has its wait aborted (the source chunk it shares with other bricks may go
// on). So a camera that moves on never leaves a pile of bricks being decoded
// behind it: what the page no longer wants leaves the queue when it says so.
import type { BrickReply, BrickRequest, QueueReport } from './brick-protocol.ts';

/** Reads a worker runs at once: enough to keep fetches overlapping, few enough that a cancel finds most reads not started. */
export const RUNNING_PER_WORKER = 3;

export type BrickRun = (request: BrickRequest, signal: AbortSignal) => Promise<{ reply: BrickReply; transfer: Transferable[] }>;

export class BrickQueue {
  readonly #waiting: BrickRequest[] = [];
  readonly #running = new Map<number, AbortController>();
  /** The most reads held at once (waiting and running): what a moving camera can leave behind. */
  #maxHeld = 0;

  constructor(
    private readonly run: BrickRun,
    private readonly reply: (m: BrickReply, transfer: Transferable[]) => void,
    /** What a read answered without running says of the meters (nothing happened). */
    private readonly idleMeter: () => BrickReply['meter'],
    readonly concurrency = RUNNING_PER_WORKER,
  ) {}

  /** Reads waiting to start. */
  get waiting(): number {
    return this.#waiting.length;
  }

  /** Reads running. */
  get running(): number {
    return this.#running.size;
  }

  /** Reads held now (waiting and running) and the most held at once; every reply carries it. */
  get report(): QueueReport {
    return { held: this.#waiting.length + this.#running.size, maxHeld: this.#maxHeld };
  }

  read(request: BrickRequest): void {
    this.#waiting.push(request);
    this.#maxHeld = Math.max(this.#maxHeld, this.#waiting.length + this.#running.size);
    this.#pump();
  }

  /** The page no longer wants read `id`: dropped if it has not started, else its wait is aborted. */
  cancel(id: number): void {
    const i = this.#waiting.findIndex((r) => r.id === id);
    if (i >= 0) {
      this.#waiting.splice(i, 1);
      this.reply(
        { type: 'fail', id, error: { name: 'AbortError', kind: 'aborted', message: 'no longer needed' }, meter: this.idleMeter() },
        [],
      );
      return;
    }
    this.#running.get(id)?.abort(new DOMException('no longer needed', 'AbortError'));
  }

  #pump(): void {
    while (this.#running.size < this.concurrency && this.#waiting.length > 0) {
      const request = this.#waiting.shift()!;
      const controller = new AbortController();
      this.#running.set(request.id, controller);
      void this.run(request, controller.signal).then(({ reply, transfer }) => {
        this.#running.delete(request.id);
        this.reply({ ...reply, queue: this.report }, transfer);
        this.#pump();
      });
    }
  }
}
