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
}

export class MeasurePanel {
  private running = false;

  constructor(
    private readonly button: HTMLButtonElement,
    private readonly list: HTMLElement,
    private readonly measure: () => Promise<MeasuredSurface | null>,
    private readonly publish: (m: MeasuredSurface | undefined) => void,
  ) {
    button.addEventListener('click', () => void this.run());
  }

  /** Another volume is on screen: the old figures go. */
  clear(): void {
    setInfoList(this.list, []);
    this.publish(undefined);
  }

  private async run(): Promise<void> {
    if (this.running) return;
    this.running = true;
    this.button.disabled = true;
    this.button.textContent = 'Measuring…';
    this.publish(undefined); // being measured
    try {
      const m = await this.measure();
      if (!m) return;
      setInfoList(this.list, measureRows(m));
      this.publish(m);
    } finally {
      this.running = false;
      this.button.disabled = false;
      this.button.textContent = 'Measure';
    }
  }
}

export function measureRows(m: MeasuredSurface): [string, string][] {
  const unit = m.voxelUnits ? 'voxel' : 'unit';
  const rows: [string, string][] = [
    ['measured', `iso ${Number(m.iso.toPrecision(6))}, ${m.triangles.toLocaleString('en-US')} triangles`],
    ['area', `${fmt(m.area)} ${unit}²`],
  ];
  if (m.enclosedVolume !== null) rows.push(['encloses', `${fmt(m.enclosedVolume)} ${unit}³`]);
  else if (m.triangles > 0)
    rows.push(['encloses', `— open surface (${m.openEdges.toLocaleString('en-US')} open edges: cut by the volume's box or a seam)`]);
  else rows.push(['encloses', '— no surface']);
  return rows;
}

function fmt(x: number): string {
  return Math.abs(x) >= 1e6 || (x !== 0 && Math.abs(x) < 1e-3) ? x.toExponential(4) : Number(x.toPrecision(6)).toLocaleString('en-US');
}
