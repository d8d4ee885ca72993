// The isosurface on the neuron page: the stack on screen is compressed on the
// GPU (zfp fixed rate from the panel, src/volume/open-volume.ts), given an
// Isosurface with its first surface (the main page's openFirstSurface) and
// drawn by the main page's SurfaceLayer. It shares the world space of the
// volume rendering and the traces: voxel (x, y, page) of the stack is voxel
// index (x, y, z) of the stream (x fastest, as the TIFF rows are) and sits at
// index * spacing, where the ray marcher puts voxel centres. The layer also
// draws into the depth pre-pass, so rays stop at the surface.
//
// Panel: show/hide, the isovalue (the main page's IsoControl: slider, number,
// block profile), colour, rate, and the surface's numbers.

import { hexToRgb } from '../../app/controls.ts';
import { formatIso } from '../../app/format.ts';
import { setInfoList } from '../../app/info-list.ts';
import { chooseIsovalue } from '../../app/iso-choice.ts';
import { loadErrorMessage, openFirstSurface, type SurfaceVolume } from '../../app/loading/first-surface.ts';
import { LoadCancelled } from '../../app/loading/read.ts';
import type { Messages } from '../../app/messages.ts';
import { computeBlockProfile } from '../../app/ui/block-profile.ts';
import { IsoControl } from '../../app/ui/iso-control.ts';
import type { GpuContext } from '../../gpu/device.ts';
import { IsosurfaceBudgetError, type IsosurfaceStats } from '../../isosurface/types.ts';
import { SurfaceLayer } from '../../render/surface-layer.ts';
import type { Viewer } from '../../render/viewer.ts';
import { openVolumeFile, type VolumeFileFacts } from '../../volume/open-volume.ts';
import { byId, formatBytes, formatCount, formatMs, type Progress } from '../common.ts';
import type { DepthPrepass } from './depth-prepass.ts';

type Vec3 = [number, number, number];

/** The stack on screen, as the encoder takes it. */
export interface StackSource {
  /** Names the stack in messages (file name, "12 TIFF files", "demo cell"). */
  name: string;
  /** Samples, shape and type (TIFF: tiffVolumeFacts; in-memory stacks: kind 'raw'). */
  facts: VolumeFileFacts;
  /** The samples of a 'raw' source (TIFF facts carry theirs). */
  bytes: Uint8Array;
  /** World size of a voxel, as the volume renderer uses it. */
  spacing: Vec3;
}

/** What the page tests read (window.neuron.surface). */
export interface SurfaceState {
  computing: boolean;
  visible: boolean;
  rate: number;
  /** The isovalue asked for. */
  isovalue?: number;
  /** The isovalue of the surface on screen (float32, as the GPU computed it). */
  drawnIsovalue?: number;
  triangles?: number;
  activeBlocks?: number;
  blockCount?: number;
  gpuMs?: number;
  compressedBytes?: number;
}

export class NeuronIsosurface {
  readonly state: SurfaceState = { computing: false, visible: true, rate: 8 };
  private current: SurfaceVolume | undefined;
  private source: StackSource | undefined;
  private build: AbortController | undefined;
  private readonly isoControl: IsoControl;
  private readonly statsList = byId('surface-stats');
  private readonly rateSelect = byId<HTMLSelectElement>('surface-rate');

  private constructor(
    private readonly gpu: GpuContext,
    private readonly viewer: Viewer,
    readonly layer: SurfaceLayer,
    private readonly messages: Messages,
    private readonly progress: Progress,
    private readonly onChange: () => void,
  ) {
    this.isoControl = new IsoControl(
      {
        slider: byId('iso-slider'),
        number: byId('iso-value'),
        profile: byId('iso-profile'),
        readout: byId('profile-readout'),
        min: byId('iso-min'),
        max: byId('iso-max'),
      },
      (iso) => {
        this.state.isovalue = iso;
        this.current?.iso.setIsovalue(iso);
      },
    );
    const show = byId<HTMLInputElement>('show-surface');
    show.addEventListener('change', () => {
      layer.visible = this.state.visible = show.checked;
      viewer.requestFrame();
      onChange();
    });
    const color = byId<HTMLInputElement>('surface-color');
    const applyColor = () => {
      layer.style.front = hexToRgb(color.value);
      viewer.requestFrame();
    };
    color.addEventListener('input', applyColor);
    applyColor();
    const rate = this.rateSelect;
    this.state.rate = Number(rate.value);
    rate.addEventListener('change', () => {
      this.state.rate = Number(rate.value);
      // The same stack at another rate: the surface on screen stays until the new one is ready.
      if (this.source) void this.compute(this.source, false);
    });
  }

  static async create(
    gpu: GpuContext,
    viewer: Viewer,
    prepass: DepthPrepass,
    messages: Messages,
    progress: Progress,
    onChange: () => void,
  ): Promise<NeuronIsosurface> {
    const layer = await SurfaceLayer.create(viewer, { depthPrepass: true });
    prepass.add(layer);
    return new NeuronIsosurface(gpu, viewer, layer, messages, progress, onChange);
  }

  /** A new stack is on screen: the old surface goes at once (it belongs to the old volume), the new one is computed. */
  setStack(source: StackSource): Promise<void> {
    this.drop();
    this.source = source;
    this.layer.voxelSize = [...source.spacing];
    return this.compute(source, true);
  }

  /** Compresses `source` at the panel's rate and computes its first surface; a newer call wins. */
  private async compute(source: StackSource, fresh: boolean): Promise<void> {
    this.build?.abort();
    const controller = new AbortController();
    this.build = controller;
    const { signal } = controller;
    const rate = this.state.rate;
    const keepIso = fresh ? undefined : this.state.isovalue;
    this.state.computing = true;
    this.isoControl.setEnabled(false);
    this.onChange();
    this.progress.start(`Isosurface of ${source.name}`);
    this.progress.set(0.2, `compressing on the GPU at ${rate} bits/value…`);
    try {
      const opened = await openVolumeFile(this.gpu.device, source.facts, source.bytes, { rate });
      if (signal.aborted) {
        opened.stream.destroy();
        throw new LoadCancelled();
      }
      const surface = await openFirstSurface(this.gpu, opened, {
        signal,
        chooseIso: (_opened, iso, ranges) => {
          const [lo, hi] = iso.info.valueRange;
          return keepIso !== undefined && keepIso >= lo && keepIso <= hi ? keepIso : chooseIsovalue(ranges, iso.info.valueRange);
        },
        onStage: (stage) =>
          this.progress.set(stage === 'ranges' ? 0.5 : 0.75, stage === 'ranges' ? 'block ranges…' : 'extracting the surface…'),
      });
      this.install(surface);
      for (const note of opened.notes) this.messages.show(note, 'info', 15000);
    } catch (e) {
      if (e instanceof LoadCancelled || signal.aborted) return;
      this.messages.show(`No isosurface: ${loadErrorMessage(source.name, e)}`);
      // A failed change of rate: the surface on screen (and its rate) stay.
      if (this.current) {
        this.state.rate = this.current.opened.rate;
        this.rateSelect.value = String(this.current.opened.rate);
      }
    } finally {
      if (this.build === controller) {
        this.build = undefined;
        this.state.computing = false;
        this.isoControl.setEnabled(this.current !== undefined);
        this.progress.done();
        this.onChange();
      }
    }
  }

  private install(v: SurfaceVolume): void {
    const old = this.current;
    this.current = v;
    const { info } = v.iso;
    v.iso.onStats((s) => {
      if (this.current === v) this.showStats(s);
    });
    v.iso.onSubmit(() => {
      if (this.current === v) this.viewer.requestFrame();
    });
    v.iso.onError((e) => {
      if (this.current !== v) return;
      this.messages.show(
        e instanceof IsosurfaceBudgetError
          ? `The isosurface of ${this.source?.name} at ${formatIso(this.state.isovalue ?? 0, info.valueRange)} needs ${formatBytes(e.neededBytes)} of GPU memory, ` +
              `more than its budget of ${formatBytes(e.budgetBytes)}; the previous surface stays.`
          : `Isosurface of ${this.source?.name}: ${e.message}`,
      );
    });
    const [lo, hi] = info.valueRange;
    this.isoControl.setVolume(info.valueRange, computeBlockProfile(v.ranges, lo, hi), v.initialIso);
    this.state.isovalue = v.initialIso;
    this.state.rate = v.opened.rate;
    this.state.compressedBytes = v.opened.compressedBytes;
    this.state.blockCount = info.blockCount;
    // Set here, not in a before-frame hook: the depth pre-pass records before such hooks would run.
    this.layer.setDrawData(v.iso.drawData);
    this.showStats(v.firstStats);
    old?.iso.destroy();
    old?.opened.stream.destroy();
  }

  private showStats(s: IsosurfaceStats): void {
    const v = this.current!;
    Object.assign(this.state, { drawnIsovalue: s.isovalue, triangles: s.triangles, activeBlocks: s.activeBlocks, gpuMs: s.gpuMs });
    const [nx, ny, nz] = v.opened.dims;
    // Against float32, what the pipeline decodes blocks to (as the main page counts it).
    const decoded = nx * ny * nz * 4;
    setInfoList(this.statsList, [
      ['triangles', formatCount(s.triangles)],
      [
        'active blocks',
        `${formatCount(s.activeBlocks)} of ${formatCount(v.iso.info.blockCount)} (${formatCount(s.occupiedBlocks)} with triangles)`,
      ],
      ['GPU time', `${formatMs(s.gpuMs)}${s.timingSource === 'timestamp-query' ? '' : ' (queue wall time)'}`],
      [
        'zfp stream',
        `${formatBytes(v.opened.compressedBytes)} at ${v.opened.rate} bits/value (${(decoded / v.opened.compressedBytes).toFixed(1)} : 1 vs float32)`,
      ],
    ]);
    this.viewer.requestFrame();
    this.onChange();
  }

  /** No surface (and none in the making). */
  private drop(): void {
    this.build?.abort();
    this.current?.iso.destroy();
    this.current?.opened.stream.destroy();
    this.current = undefined;
    this.source = undefined;
    this.layer.setDrawData(undefined);
    this.isoControl.setEnabled(false);
    this.statsList.replaceChildren();
    Object.assign(this.state, {
      isovalue: undefined,
      drawnIsovalue: undefined,
      triangles: undefined,
      activeBlocks: undefined,
      blockCount: undefined,
      gpuMs: undefined,
      compressedBytes: undefined,
    });
    this.viewer.requestFrame();
  }
}
