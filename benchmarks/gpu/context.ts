// What every section of bench:gpu shares: the device, the run's plan (full or
// --smoke sizes), the deadline, where the data is, and the record each section
// writes into: figures (every one must be present and positive), checks (GPU
// results against a reference computed elsewhere), tables and notes.
import type { GpuContext } from '../../src/gpu/device.ts';

export interface Figure {
  section: string;
  name: string;
  value: number;
  unit: string;
}

export interface Check {
  section: string;
  name: string;
  ok: boolean;
  /** What was compared with what, and the numbers. */
  detail: string;
}

export interface SectionRecord {
  name: string;
  status: 'ran' | 'skipped' | 'failed';
  /** Why skipped or failed (the error's message). */
  reason?: string;
  seconds: number;
  /** The section's own data (per size, per volume, ...). */
  data?: unknown;
}

export interface Table {
  title: string;
  header: string[];
  rows: (string | number)[][];
}

export interface Plan {
  smoke: boolean;
  /** Primitive sizes as powers of two. */
  primitiveExponents: number[];
  primitiveRepeats: number;
  /** Edge of the generated in-core volume (the converter's gen: field). */
  genEdge: number;
  /** Rate of the generated in-core volume's zfp stream. */
  genRate: number;
  /** Isovalues per benchmark mode (random, sweep up, sweep down) on each volume. */
  surfacesPerMode: number;
  /** Cap per mode, seconds. */
  modeCapSeconds: number;
  /** Naive GPU MC surfaces, paired with the first random ones. */
  naiveSurfaces: number;
  decodeRepeats: number;
  /** Edge of the generated store streamed (converted with the project's converter). */
  storeEdge: number;
  storeBudgetBytes: number;
  /** The in-core volume with VTK references: its file under data/volumes. */
  referenceVolume: string;
  /** A zfp file under data/volumes whose zfpy-decoded SHA-256 mc.json gives. */
  decodeVolume: string;
}

export const FULL_PLAN: Plan = {
  smoke: false,
  primitiveExponents: [20, 22, 24, 26],
  primitiveRepeats: 7,
  genEdge: 512,
  genRate: 8,
  surfacesPerMode: 60,
  modeCapSeconds: 12,
  naiveSurfaces: 12,
  decodeRepeats: 8,
  storeEdge: 1024,
  storeBudgetBytes: 256 * 2 ** 20,
  referenceVolume: 'bonsai_256x256x256_float32.rate4.zfp',
  decodeVolume: 'bonsai_256x256x256_float32.rate4.zfp',
};

/** Tiny sizes: the same code on SwiftShader inside npm test, in well under two minutes. */
export const SMOKE_PLAN: Plan = {
  smoke: true,
  primitiveExponents: [10, 12],
  primitiveRepeats: 3,
  genEdge: 64,
  genRate: 8,
  surfacesPerMode: 4,
  modeCapSeconds: 10,
  naiveSurfaces: 2,
  decodeRepeats: 3,
  storeEdge: 128,
  storeBudgetBytes: 64 * 2 ** 20,
  referenceVolume: 'fuel_64x64x64_float32.raw',
  decodeVolume: 'hydrogen_atom_128x128x128_float32.rate8.zfp',
};

export interface Paths {
  /** The checkout (for the converter's sources). */
  root: string;
  /** A folder laid out as shared/data: volumes/, reference/mc.json. */
  data: string;
  /** Scratch space (generated stores). */
  work: string;
  /** Python with zarr, numcodecs, zfpy and dask, for the converter. */
  python: string;
}

export class BenchRun {
  readonly figures: Figure[] = [];
  readonly checks: Check[] = [];
  readonly sections: SectionRecord[] = [];
  readonly tables: Table[] = [];
  readonly notes: string[] = [];
  readonly started = performance.now();

  constructor(
    readonly gpu: GpuContext,
    readonly plan: Plan,
    readonly paths: Paths,
    /** Seconds from the start after which no section starts. */
    readonly maxSeconds: number,
  ) {}

  get elapsedSeconds(): number {
    return (performance.now() - this.started) / 1000;
  }

  get secondsLeft(): number {
    return this.maxSeconds - this.elapsedSeconds;
  }

  /**
   * Runs `record`'s work untimed for a while before it is measured: a GPU
   * that idled (while the CPU made the next volume) runs at a fraction of its
   * clock for the first milliseconds, and a sub-millisecond kernel timed
   * then reads several times slower (bonsai's decode: 53 against 255 GB/s
   * between two runs on an H200). 150 ms on a GPU; one pass in a smoke run.
   */
  async warmUp(record: (encoder: GPUCommandEncoder) => void): Promise<void> {
    const { device } = this.gpu;
    const until = performance.now() + (this.plan.smoke ? 0 : 150);
    do {
      const encoder = device.createCommandEncoder({ label: 'benchGpu.warmUp' });
      record(encoder);
      device.queue.submit([encoder.finish()]);
      await device.queue.onSubmittedWorkDone();
    } while (performance.now() < until);
  }

  figure(section: string, name: string, value: number, unit: string): void {
    this.figures.push({ section, name, value, unit });
  }

  check(section: string, name: string, ok: boolean, detail: string): void {
    this.checks.push({ section, name, ok, detail });
    console.log(`  check ${ok ? 'ok  ' : 'FAIL'} ${name}: ${detail}`);
  }

  table(t: Table): void {
    this.tables.push(t);
  }

  /**
   * Runs one section unless fewer than `needsSeconds` are left; a failure is
   * recorded (with its message) and the run goes on with the next section.
   */
  async section(name: string, needsSeconds: number, body: () => Promise<unknown>): Promise<void> {
    const t0 = performance.now();
    if (this.secondsLeft < needsSeconds) {
      const reason = `${this.secondsLeft.toFixed(0)} s left of the run's ${this.maxSeconds} s, the section needs about ${needsSeconds} s`;
      console.log(`\n== ${name}: skipped (${reason})`);
      this.sections.push({ name, status: 'skipped', reason, seconds: 0 });
      return;
    }
    console.log(`\n== ${name} (${this.elapsedSeconds.toFixed(0)} s into the run)`);
    try {
      const data = await body();
      this.sections.push({ name, status: 'ran', seconds: (performance.now() - t0) / 1000, data });
    } catch (e) {
      const err = e as Error;
      console.error(`${name} failed: ${err.stack ?? err.message}`);
      this.sections.push({ name, status: 'failed', reason: err.message, seconds: (performance.now() - t0) / 1000 });
    }
  }
}
