// Opening a volume, from the user's file (drop, picker), a same-origin URL or
// the built-in generator, to a computed first surface. Only a volume that got
// all the way is handed to `onLoaded`; on any failure or cancel everything
// made so far is freed, the message names the file, and the current volume
// stays. A newer load cancels an older one. `reload()` opens the last volume
// that got all the way again, with the answers the user gave the form (the
// page does so on a new device after the old one was lost).

import type { GpuContext } from '../../gpu/device.ts';
import {
  inspectTiffStack,
  inspectVolumeFile,
  openDefaultVolume,
  openVolumeFile,
  type OpenedVolume,
  type OpenPhase,
  type VolumeFileFacts,
} from '../../volume/open-volume.ts';
import type { PageIsosurface } from '../engine.ts';
import { formatBytes } from '../format.ts';
import type { ProgressView } from '../ui/progress.ts';
import type { VolumeForm } from '../ui/volume-form.ts';
import { loadErrorMessage, openFirstSurface, type SurfaceVolume } from './first-surface.ts';
import { fetchVolume, fileNameOfUrl, LoadCancelled, readFile, resolveSameOrigin } from './read.ts';

export interface LoadedVolume extends SurfaceVolume {
  /** How long the whole load took, ms. */
  loadMs: number;
}

export interface LoaderDeps {
  /** The device to load on (the page's current one). */
  gpu: () => GpuContext;
  progress: ProgressView;
  form: VolumeForm;
  /** The isovalue a volume opens at. */
  chooseIso: (opened: OpenedVolume, iso: PageIsosurface, ranges: Float32Array) => number;
  /** Applied to every new Isosurface before its first surface. */
  memoryBudget: () => number | undefined;
  onLoaded: (volume: LoadedVolume) => void;
  onError: (message: string) => void;
  onCancelled: (what: string) => void;
  /** What the user should know about a volume that opened (OpenedVolume.notes: NaN/Inf replaced, ...). */
  onNotice?: (message: string) => void;
  onBusy: (busy: boolean) => void;
}

const PHASE_TEXT: Record<OpenPhase, string> = {
  upload: 'Uploading the stream to the GPU…',
  compress: 'Choosing the rate from the data and compressing on the GPU…',
};

type Produce = (signal: AbortSignal, progress: (text: string, f?: number) => void) => Promise<OpenedVolume | undefined>;

export class VolumeLoader {
  private generation = 0;
  private controller: AbortController | undefined;
  /** The last load that got all the way, and the form's answer it used. */
  private last: { what: string; produce: Produce; answer: object | undefined } | undefined;
  /** The form's answer of the running load; the one replayed by reload(). */
  private answer: object | undefined;
  private replay: object | undefined;

  constructor(private readonly deps: LoaderDeps) {}

  get busy(): boolean {
    return this.controller !== undefined;
  }

  cancel(): void {
    this.controller?.abort();
    this.deps.form.cancel();
  }

  loadFile(file: File): Promise<void> {
    return this.run(file.name, async (signal, progress) => {
      const bytes = await readFile(
        file,
        (done, total) =>
          progress(`Reading ${formatBytes(done)} of ${formatBytes(total ?? file.size)}…`, total ? (done / total) * 0.3 : undefined),
        signal,
      );
      return this.open(file.name, bytes, signal, progress);
    });
  }

  /** Several files: a TIFF stack when they are all TIFF (ordered by name), else the first one. */
  loadFiles(files: File[]): Promise<void> {
    if (files.length > 1 && files.every((f) => /\.tiff?$/i.test(f.name))) {
      return this.run(`${files.length} TIFF files (a stack)`, async (signal, progress) => {
        progress('Reading the TIFF stack…', undefined);
        const facts = await inspectTiffStack(files.map((f) => ({ name: f.name, bytes: f })));
        return this.openFacts(facts, new Uint8Array(0), signal, progress);
      });
    }
    return this.loadFile(files[0]);
  }

  loadUrl(url: string): Promise<void> {
    let resolved: URL;
    try {
      resolved = resolveSameOrigin(url);
    } catch (e) {
      this.deps.onError((e as Error).message);
      return Promise.resolve();
    }
    const name = fileNameOfUrl(resolved);
    return this.run(name, async (signal, progress) => {
      const bytes = await fetchVolume(
        resolved,
        (done, total) =>
          progress(
            `Downloading ${formatBytes(done)}${total ? ` of ${formatBytes(total)}` : ''}…`,
            total ? (done / total) * 0.3 : undefined,
          ),
        signal,
      );
      return this.open(name, bytes, signal, progress);
    });
  }

  loadDefault(): Promise<void> {
    return this.run('Built-in volume', async (_signal, progress) => {
      progress('Generating and compressing on the GPU…', undefined);
      return openDefaultVolume(this.deps.gpu().device, { maxStreamBytes: this.streamBudget() });
    });
  }

  /** A rate chosen from the data makes a stream of at most half the memory budget (the cache and the surface get the rest). */
  private streamBudget(): number | undefined {
    const budget = this.deps.memoryBudget();
    return budget === undefined ? undefined : budget / 2;
  }

  /** Whether there is a last volume to open again. */
  get canReload(): boolean {
    return this.last !== undefined;
  }

  /** Opens the last volume that got all the way again (same file, URL or generator; the form's answers replayed). */
  reload(): Promise<void> {
    const last = this.last;
    if (!last) return Promise.resolve();
    this.replay = last.answer;
    return this.run(last.what, last.produce);
  }

  private async open(
    fileName: string,
    bytes: Uint8Array,
    signal: AbortSignal,
    progress: (text: string, f?: number) => void,
  ): Promise<OpenedVolume | undefined> {
    progress('Checking the file…', 0.3);
    const facts: VolumeFileFacts = await inspectVolumeFile(fileName, bytes);
    return this.openFacts(facts, bytes, signal, progress);
  }

  private async openFacts(
    facts: VolumeFileFacts,
    bytes: Uint8Array,
    signal: AbortSignal,
    progress: (text: string, f?: number) => void,
  ): Promise<OpenedVolume | undefined> {
    let request = {};
    if (facts.missing.length > 0 || facts.compresses) {
      progress('Waiting for the volume’s description…', 0.3);
      const replayed = this.replay;
      this.replay = undefined;
      const answer = replayed ?? (await this.deps.form.ask(facts));
      if (!answer || signal.aborted) throw new LoadCancelled();
      request = answer;
      this.answer = answer;
    }
    return openVolumeFile(this.deps.gpu().device, facts, bytes, request, {
      onPhase: (phase) => progress(PHASE_TEXT[phase], undefined),
      maxStreamBytes: this.streamBudget(),
    });
  }

  private async run(what: string, produce: Produce): Promise<void> {
    const replay = this.replay;
    this.cancel();
    this.replay = replay;
    this.answer = undefined;
    const job = ++this.generation;
    const controller = new AbortController();
    this.controller = controller;
    const { signal } = controller;
    const { progress } = this.deps;
    const gpu = this.deps.gpu();
    const started = performance.now();
    progress.start(what, () => this.cancel());
    this.deps.onBusy(true);
    const set = (text: string, f?: number) => {
      if (job === this.generation) progress.set(text, f);
    };
    try {
      const opened = await produce(signal, set);
      if (!opened) throw new LoadCancelled();
      // openFirstSurface owns the stream from here (and frees it on failure or cancel).
      const surface = await openFirstSurface(gpu, opened, {
        memoryBudget: this.deps.memoryBudget(),
        chooseIso: this.deps.chooseIso,
        signal,
        onStage: (stage) => (stage === 'ranges' ? set('Computing block ranges…', 0.65) : set('Extracting the surface…', 0.8)),
      });
      try {
        this.last = { what, produce, answer: this.answer };
        this.deps.onLoaded({ ...surface, loadMs: performance.now() - started });
        for (const note of surface.opened.notes) this.deps.onNotice?.(note);
      } catch (e) {
        surface.iso.destroy();
        surface.opened.stream.destroy();
        throw e;
      }
    } catch (e) {
      if (job !== this.generation) {
        // Replaced by a newer load: nothing to say.
      } else if (e instanceof LoadCancelled || signal.aborted) this.deps.onCancelled(what);
      else this.deps.onError(loadErrorMessage(what, e));
    } finally {
      if (job === this.generation) {
        this.controller = undefined;
        progress.finish();
        this.deps.onBusy(false);
      }
    }
  }
}
