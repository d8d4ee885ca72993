// "Measure": the area and enclosed volume of the surface on screen, in the
// page's world units (voxel size applied), read from the GPU's mesh on demand
// (a big surface is many MB to read, so not on every isovalue). A surface
// the volume's box cuts, or a store's pieces that meet at level seams, is
// open: the panel says so instead of a volume. What was measured is labelled
// with its isovalue; opening another volume clears it.
import type { SurfaceMeasure } from '../../mc/mesh-measure.ts';
import { setInfoList } from '../info-list.ts';

export interface MeasuredSurface extends SurfaceMeasure {
  iso: number;
  /** Voxel size 1 and no origin: the units are voxels. */
  voxelUnits: boolean;
  /** The surface the slider moves. */
  selected?: boolean;
  color?: readonly number[];
  opacity?: number;
}

export class MeasurePanel {
  private running = false;
  #last: MeasuredSurface[] = [];

  constructor(
    private readonly els: { button: HTMLButtonElement; list: HTMLElement; json: HTMLButtonElement; csv: HTMLButtonElement },
    /** Every visible surface (cut by the clip), or null when nothing is open or it failed. */
    private readonly measure: () => Promise<MeasuredSurface[] | null>,
    private readonly publish: (all: MeasuredSurface[]) => void,
    /** The JSON / CSV downloads (the caller adds what else it knows: volume, clip, picks). */
    private readonly save: (format: 'json' | 'csv', all: MeasuredSurface[]) => void,
  ) {
    els.button.addEventListener('click', () => void this.run());
    els.json.addEventListener('click', () => this.save('json', this.#last));
    els.csv.addEventListener('click', () => this.save('csv', this.#last));
    this.#enableSaves();
  }

  /** Another volume is on screen: the old figures go. */
  clear(): void {
    this.#last = [];
    setInfoList(this.els.list, []);
    this.publish([]);
    this.#enableSaves();
  }

  private async run(): Promise<void> {
    if (this.running) return;
    this.running = true;
    const { button } = this.els;
    button.disabled = true;
    button.textContent = 'Measuring…';
    this.publish([]); // being measured
    try {
      const all = await this.measure();
      if (!all) return;
      this.#last = all;
      setInfoList(this.els.list, all.flatMap(measureRows));
      this.publish(all);
    } finally {
      this.running = false;
      button.disabled = false;
      button.textContent = 'Measure';
      this.#enableSaves();
    }
  }

  #enableSaves(): void {
    this.els.json.disabled = this.els.csv.disabled = this.#last.length === 0;
  }
}

export function measureRows(m: MeasuredSurface): [string, string][] {
  const unit = m.voxelUnits ? 'voxel' : 'unit';
  const name = `iso ${Number(m.iso.toPrecision(6))}${m.selected ? ' (selected)' : ''}`;
  const rows: [string, string][] = [
    [name, `${m.triangles.toLocaleString('en-US')} triangles`],
    ['area', `${fmt(m.area)} ${unit}²`],
  ];
  if (m.enclosedVolume !== null) rows.push(['encloses', `${fmt(m.enclosedVolume)} ${unit}³`]);
  else if (m.triangles > 0)
    rows.push([
      'encloses',
      `— open surface (${m.openEdges.toLocaleString('en-US')} open edges: cut by the volume's box, the clip or a seam)`,
    ]);
  else rows.push(['encloses', '— no surface']);
  return rows;
}

/** One row per surface: isovalue, colour, opacity, triangles, area, enclosed volume (empty: open), open edges. */
export function measuresToCsv(all: MeasuredSurface[]): string {
  const hex = (c: readonly number[] | undefined) =>
    c
      ? c
          .map((v) =>
            Math.round(v * 255)
              .toString(16)
              .padStart(2, '0'),
          )
          .join('')
      : '';
  const lines = ['iso,selected,color,opacity,triangles,area,enclosed_volume,open_edges,units'];
  for (const m of all) {
    lines.push(
      [
        m.iso,
        m.selected ? 1 : 0,
        hex(m.color),
        m.opacity ?? 1,
        m.triangles,
        m.area,
        m.enclosedVolume ?? '',
        m.openEdges,
        m.voxelUnits ? 'voxel' : 'world',
      ].join(','),
    );
  }
  return `${lines.join('\n')}\n`;
}

function fmt(x: number): string {
  return Math.abs(x) >= 1e6 || (x !== 0 && Math.abs(x) < 1e-3) ? x.toExponential(4) : Number(x.toPrecision(6)).toLocaleString('en-US');
}
