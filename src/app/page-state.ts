// What the page exposes as window.zfpiso: for the end-to-end tests, and handy
// in the console. Plain data and getters only.
import type { BenchResult } from '../bench/harness.ts';
import type { AdapterSummary } from '../gpu/device.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { CameraState } from '../render/camera.ts';
import type { Dims } from '../core/naming.ts';
import type { MeasuredSurface } from './ui/measure-panel.ts';
import type { SurfaceSpec } from './url-state.ts';
import type { Clip } from '../core/clip.ts';
import type { PickedPoint } from './ui/pick-panel.ts';

export interface PageVolumeState {
  name: string;
  fileName: string;
  kind: string;
  dims: Dims;
  rate: number;
  valueRange: [number, number];
  blockCount: number;
  /** World size of a voxel along x, y, z (the file's, or what the user set). */
  spacing: [number, number, number];
}

export interface PageState {
  status: 'loading' | 'ready' | 'error';
  adapter?: AdapterSummary;
  framesDrawn: () => number;
  camera?: () => CameraState;
  volume?: PageVolumeState;
  /** The isovalue the user chose (slider). */
  iso?: number;
  /** The newest statistics received (the drawn surface). */
  stats?: IsosurfaceStats;
  /** Statistics received so far. */
  statsCount: number;
  /** Volumes loaded so far (the built-in one included). */
  loads: number;
  loading: boolean;
  /** Every message shown to the user, in order. */
  messages: string[];
  bench?: BenchResult;
  /** The surfaces (several for an in-core volume), the one the slider moves, and the bytes their copies hold. */
  surfaces?: { entries: (SurfaceSpec & { triangles?: number })[]; selected: number; copyBytes: number };
  /** Points picked on the surface (Pick points) and the distance between the two. */
  picks?: { points: PickedPoint[]; distance: number | null };
  /** Blocks decoded for the caps of the clip (0: no caps). */
  capBlocks?: number;
  /** The clip on screen (src/core/clip.ts), undefined when nothing is cut. */
  clip?: Clip;
  /** How the selected surface is drawn: its triangles, or ray cast in the block cache. */
  draw?: 'mesh' | 'rays';
  /** Whether the last frame drew the selected surface by rays (draw rays, and what they read holds the surface on screen). */
  raysDrawn?: boolean;
  /** How many times a store's rays were read back and asked for finer chunks where they hit (a cut for rays). */
  raysGuided?: number;
  /** Whether the rays of a store's final step wait to be read back (or are being read) for a cut for rays. */
  raysGuiding?: boolean;
  /** The last "Measure": every visible surface (empty while measuring or after another volume opened). */
  measures?: MeasuredSurface[];
  /** The last "Measure" of the surface (cleared when another volume opens). */
  measure?: MeasuredSurface;
  benchRunning: boolean;
  /** Devices lost so far (each followed by a new device and the volume opened again). */
  deviceLosses?: number;
  /** Destroys the page's device, as a driver reset would lose it (tests of the recovery). */
  loseDevice?: () => void;
}

declare global {
  interface Window {
    zfpiso?: PageState;
  }
}

export function publishPageState(): PageState {
  const state: PageState = {
    status: 'loading',
    framesDrawn: () => 0,
    statsCount: 0,
    loads: 0,
    loading: false,
    messages: [],
    benchRunning: false,
  };
  window.zfpiso = state;
  return state;
}
