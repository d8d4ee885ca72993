// The JSON that `npm run bench:paper` writes (benchmarks/results/*.json) and
// report.ts turns into the Markdown report.
import type { AdapterSummary } from '../../src/gpu/device.ts';
import type { SerialTimes } from '../../src/examples/paper-bench/measure.ts';
import type { BlockResult } from './block.ts';
import type { ZfpRateResult } from './zfp.ts';

export interface SerialEntry {
  volume: string;
  label: string;
  isovalues: number[];
  native?: SerialTimes;
  wasmNode: SerialTimes;
  jsNode: SerialTimes;
  wasmChromium?: SerialTimes;
  jsChromium?: SerialTimes;
  means: { native?: number; wasmNode: number; jsNode: number; wasmChromium?: number; jsChromium?: number };
}

export interface NaiveEntry {
  volume: string;
  label: string;
  paperName?: string;
  isovalues: number[];
  ms: number[];
  wallMs: number[];
  triangles: number[];
  activeCells: number[];
  stagesMeanMs: Record<string, number>;
  trianglesMatchSerial: boolean;
  memoryBytes: number;
  /** Serial native mean over the same isovalues (first discarded). */
  serialNativeMs?: number;
  chromiumMs?: number[];
  cappedAt?: number;
}

export interface PaperBenchResult {
  benchmark: 'paper';
  version: 1;
  date: string;
  mode: 'full' | 'quick';
  command: string;
  limits: { seconds: number };
  durations: { totalSeconds: number; sections: Record<string, number> };
  machine: {
    cpu: string;
    cores: number;
    memoryGiB: number;
    node: string;
    dawn: string;
    platform: string;
    loadAverage: { start: number[]; end: number[] };
  };
  adapter: AdapterSummary;
  adapterDescription: string;
  adapterSlug: string;
  gpuTiming: string;
  chromium: { version?: string; userAgent?: string; flags: string[]; hardwareConcurrency?: number; error?: string };
  serialNative: { compiler?: string; error?: string };
  settings: {
    seed: number;
    serialCounts: number;
    naiveCounts: Record<string, number>;
    blockCounts: Record<string, number>;
    zfpRuns: number;
    zfpRates: number[];
    plan: Record<string, unknown>;
  };
  volumes: {
    key: string;
    label: string;
    file: string;
    how: string;
    dims: readonly number[];
    rate: number;
    range: [number, number];
    rangeSource: string;
    dataRange: [number, number];
  }[];
  serial: SerialEntry[];
  naive: (NaiveEntry & { paperName?: string })[];
  zfp: ZfpRateResult[];
  block: (BlockResult & { trianglesMatchSerial?: boolean; cappedModes: string[] })[];
  headline: {
    serial: {
      wasmNodeVsNative?: number;
      jsNodeVsNative?: number;
      wasmChromiumVsNative?: number;
      jsChromiumVsNative?: number;
      jsNodeVsWasmNode?: number;
      jsChromiumVsWasmChromium?: number;
    };
    naiveVsBlock: {
      volume: string;
      label: string;
      surfaces: number;
      naiveMs: number;
      blockMs: number;
      ratio: number;
      blockRandomAllMs: number;
    }[];
    zfp: { rate: number; webgpuVsSerial: number; wasmNodeVsSerial: number; wasmChromiumVsSerial?: number }[];
  };
  notes: string[];
  paperCheck: string[] | null;
  errors: { section: string; volume?: string; message: string }[];
}
