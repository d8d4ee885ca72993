// What the store stream tells its listeners (stream/store-stream.ts, planned
// level by level or by the view):
// progress (fetching, computing, shown, stopped with its cause), what is
// shown, and errors (a chunk that failed, each once; a GPU error).
import type { StreamProgress } from './stream-port.ts';

export class StreamEvents<Shown> {
  readonly #progress = new Set<(p: StreamProgress) => void>();
  readonly #shown = new Set<(s: Shown) => void>();
  readonly #errors = new Set<(e: Error) => void>();

  onProgress(l: (p: StreamProgress) => void): () => void {
    this.#progress.add(l);
    return () => this.#progress.delete(l);
  }

  onShown(l: (s: Shown) => void): () => void {
    this.#shown.add(l);
    return () => this.#shown.delete(l);
  }

  onError(l: (e: Error) => void): () => void {
    this.#errors.add(l);
    return () => this.#errors.delete(l);
  }

  progress(p: StreamProgress): void {
    for (const l of this.#progress) l(p);
  }

  shown(s: Shown): void {
    for (const l of this.#shown) l(s);
  }

  error(e: Error): void {
    for (const l of this.#errors) l(e);
  }

  /** Refinement stopped at `level` (the surface `iso` stays on screen): why, its cause, and when it is tried again. */
  stopped(
    iso: number,
    level: number,
    reason: string,
    cause: NonNullable<StreamProgress['cause']>,
    bytesFetched: number,
    retryInMs?: number,
  ): void {
    this.progress({
      iso,
      level,
      chunksDone: 0,
      chunksNeeded: 0,
      bytesFetched,
      phase: 'stopped',
      reason,
      cause,
      ...(retryInMs !== undefined ? { retryInMs } : {}),
    });
  }
}
