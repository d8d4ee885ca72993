// Messages between the page and its brick workers (brick-worker.ts, brick-pool.ts).
import type { ChunkLevelLayout } from '../types.ts';
import type { StoreSpec } from './store-spec.ts';

export interface BrickInit {
  type: 'init';
  spec: StoreSpec;
  format: 2 | 3;
  /** Per level: what the worker cannot read from the metadata itself (the chosen axes, the brick layout). */
  levels: {
    path: string;
    spatial: [number, number, number];
    fixed: [number, number][];
    chunkXYZ: [number, number, number];
    layout: ChunkLevelLayout;
  }[];
  cacheBytes: number;
}

export interface BrickRequest {
  type: 'read';
  id: number;
  level: number;
  brick: number;
}

/** The page no longer wants read `id` (its request was aborted): dropped before it is fetched or decoded (brick-queue.ts). */
export interface BrickCancel {
  type: 'cancel';
  id: number;
}

/** What the worker's store did since its previous reply. */
export interface MeterDelta {
  bytes: number;
  requests: number;
  retries: number;
  failed: number;
}

/** A worker's queue when it answers: reads it holds (waiting and running, cancelled ones gone) and the most it has held at once. */
export interface QueueReport {
  held: number;
  maxHeld: number;
}

export type BrickReply =
  | {
      type: 'done';
      id: number;
      bytes: Uint8Array;
      /** The worker's [min, max] of source values over the level's bricks it read. */
      range: [number, number];
      /** The worker's decode counters (totals). */
      decode: { chunksDecoded: number; bytesDecoded: number; decodeMs: number; nonFinite: number };
      meter: MeterDelta;
      queue?: QueueReport;
    }
  | { type: 'fail'; id: number; error: { name: string; kind: string | null; message: string }; meter: MeterDelta; queue?: QueueReport };
