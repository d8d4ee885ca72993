// The list of surfaces: per row the selection (the slider moves the selected
// one), colour, isovalue, opacity, visibility, move up and remove; "Add
// surface" under it. Rebuilt from the SurfaceSet on every change (at most 8
// rows); the controls call back into the set.
import { hexToRgb } from '../controls.ts';
import { el } from '../dom.ts';
import { MAX_SURFACES, type SurfaceSet } from '../surfaces/surface-set.ts';

export class SurfacesPanel {
  constructor(
    private readonly list: HTMLElement,
    private readonly addButton: HTMLButtonElement,
    private readonly note: HTMLElement,
    private readonly set: () => SurfaceSet,
  ) {
    addButton.addEventListener('click', () => void this.set().add());
  }

  render(): void {
    const set = this.set();
    const rows = set.entries.map((e, i) => {
      const select = el('input', {
        type: 'radio',
        name: 'surface-selected',
        checked: e === set.shownEntry,
        title: 'The slider moves this surface',
      });
      select.addEventListener('change', () => void set.select(i));
      const colour = el('input', { type: 'color', value: rgbToHex(e.color), title: 'Colour' });
      colour.addEventListener('input', () => set.setStyle(i, { color: hexToRgb(colour.value) }));
      const opacity = el('input', { type: 'range', min: '0.05', max: '1', step: '0.05', value: String(e.opacity), title: 'Opacity' });
      opacity.setAttribute('aria-label', `Opacity of surface ${i + 1}`);
      opacity.addEventListener('input', () => set.setStyle(i, { opacity: Number(opacity.value) }));
      const visible = el('input', { type: 'checkbox', checked: e.visible, title: 'Shown' });
      visible.addEventListener('change', () => set.setStyle(i, { visible: visible.checked }));
      const up = el('button', { type: 'button', textContent: '↑', title: 'Move up', disabled: i === 0 });
      up.addEventListener('click', () => set.moveUp(i));
      const remove = el('button', { type: 'button', textContent: '×', title: 'Remove', disabled: set.entries.length === 1 });
      remove.addEventListener('click', () => void set.remove(i));
      const iso = el('span', {
        className: 'surface-iso',
        // a copy let go for the budget: listed, not drawn until selected again
        textContent: `${Number.isFinite(e.iso) ? String(Number(e.iso.toPrecision(6))) : '—'}${set.isDrawn(e) ? '' : ' (not kept: select)'}`,
      });
      const row = el(
        'li',
        { className: e === set.shownEntry ? 'surface-row selected' : 'surface-row' },
        select,
        colour,
        iso,
        opacity,
        visible,
        up,
        remove,
      );
      row.dataset.surface = String(i);
      return row;
    });
    this.list.replaceChildren(...rows);
    this.addButton.disabled = !set.canAdd;
    this.note.textContent =
      set.entries.length >= MAX_SURFACES
        ? `${MAX_SURFACES} surfaces at most.`
        : set.canAdd || set.entries.length > 1
          ? ''
          : 'This volume shows one surface.';
  }
}

export function rgbToHex(c: readonly number[]): string {
  return `#${c
    .map((v) =>
      Math.round(Math.min(1, Math.max(0, v)) * 255)
        .toString(16)
        .padStart(2, '0'),
    )
    .join('')}`;
}
