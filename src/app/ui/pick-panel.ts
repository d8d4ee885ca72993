// Picking: with "Pick points" on, a click on a surface (see-through ones
// included) shows the point in voxels of level 0 and in world units and the
// volume's value there (the trilinear value of the decoded voxels around it:
// zfp/probe.ts; a streamed store: from the finest level of the step on
// screen holding the point, and which level that was); a second
// click the second point and the distance between them (world units, voxel
// size applied). A third click starts again.
import { setInfoList } from '../info-list.ts';

export interface PickedPoint {
  /** Level-0 voxel coordinates. */
  voxel: [number, number, number];
  world: [number, number, number];
  /** Null where the volume's values are not at hand (a store's step let go of its chunks). */
  value: number | null;
  /** A store: the level the value was read from. */
  level?: number;
}

export class PickPanel {
  #points: PickedPoint[] = [];

  constructor(
    private readonly toggle: HTMLInputElement,
    private readonly list: HTMLElement,
    /** The point under (u, v) of the canvas, or null where no surface is. */
    private readonly pickAt: (u: number, v: number) => Promise<PickedPoint | null>,
    private readonly publish: (points: PickedPoint[], distance: number | null) => void,
  ) {
    toggle.addEventListener('change', () => {
      if (!toggle.checked) this.clear();
    });
  }

  get active(): boolean {
    return this.toggle.checked;
  }

  /** A click on the canvas (fractions of it from its top left). */
  async click(u: number, v: number): Promise<void> {
    if (!this.active) return;
    const p = await this.pickAt(u, v);
    if (!p) return;
    if (this.#points.length >= 2) this.#points = [];
    this.#points.push(p);
    this.#show();
  }

  clear(): void {
    this.#points = [];
    this.#show();
  }

  #show(): void {
    const rows: [string, string][] = [];
    const fmt = (x: number) => Number(x.toPrecision(6)).toLocaleString('en-US');
    this.#points.forEach((p, i) => {
      const name = i === 0 ? 'A' : 'B';
      rows.push([`${name} voxel`, p.voxel.map(fmt).join(', ')]);
      rows.push([`${name} world`, p.world.map(fmt).join(', ')]);
      const from = p.level !== undefined && p.level > 0 ? ` (level ${p.level})` : '';
      rows.push([`${name} value`, p.value === null ? '— (not resident)' : `${fmt(p.value)}${from}`]);
    });
    const d = this.distance;
    if (d !== null) rows.push(['distance', fmt(d)]);
    setInfoList(this.list, rows);
    this.publish([...this.#points], d);
  }

  /** |A - B| in world units, once two points are picked. */
  get distance(): number | null {
    if (this.#points.length < 2) return null;
    const [a, b] = this.#points;
    return Math.hypot(a.world[0] - b.world[0], a.world[1] - b.world[1], a.world[2] - b.world[2]);
  }
}
