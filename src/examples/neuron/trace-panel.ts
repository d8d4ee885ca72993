// The neuron page's trace list (visibility, colour swatch, samples, remove)
// and the legend of SWC structure types with their counts.
import { formatCount } from '../../app/format.ts';
import { swcTypeColor, swcTypeName } from '../../loaders/swc.ts';
import type { Trace } from './swc-layer.ts';

export interface ListedTrace extends Trace {
  name: string;
}

const rgb = (c: readonly number[]) => `rgb(${c.map((x) => Math.round(x * 255)).join(',')})`;

/** Rebuilds the list; `onChange` runs after a checkbox or a remove button changed `traces`. */
export function renderTraceList(list: HTMLElement, traces: ListedTrace[], onChange: () => void): void {
  list.replaceChildren(
    ...traces.map((t, i) => {
      const li = document.createElement('li');
      const label = document.createElement('label');
      const check = document.createElement('input');
      check.type = 'checkbox';
      check.checked = t.visible;
      check.addEventListener('change', () => {
        t.visible = check.checked;
        onChange();
      });
      const swatch = document.createElement('span');
      swatch.className = 'swatch';
      swatch.style.cssText = `display:inline-block;width:9px;height:9px;border-radius:2px;margin:0 5px;background:${rgb(t.color)}`;
      const name = document.createElement('span');
      name.textContent = t.name;
      label.append(check, swatch, name);
      const meta = document.createElement('span');
      meta.textContent = `${formatCount(t.tree.count)} samples `;
      const remove = document.createElement('button');
      remove.type = 'button';
      remove.textContent = '×';
      remove.title = 'Remove this trace';
      remove.style.cssText = 'padding:0 5px;margin-left:4px';
      remove.addEventListener('click', () => {
        traces.splice(i, 1);
        onChange();
      });
      meta.append(remove);
      li.append(label, meta);
      return li;
    }),
  );
  if (traces.length === 0) {
    const li = document.createElement('li');
    li.textContent = 'No traces: drop .swc files.';
    list.append(li);
  }
}

/** The structure types of the visible traces with how many traces have each (only when colouring by type). */
export function renderTraceLegend(legend: HTMLElement, traces: readonly Trace[], byType: boolean): void {
  legend.replaceChildren();
  if (!byType || traces.length === 0) return;
  const counts = new Map<number, number>();
  for (const t of traces) if (t.visible) for (const type of t.tree.types) counts.set(type, (counts.get(type) ?? 0) + 1);
  const grid = document.createElement('div');
  grid.className = 'legend';
  for (const [type, n] of [...counts].sort((a, b) => a[0] - b[0])) {
    const sw = document.createElement('span');
    sw.className = 'swatch';
    sw.style.background = rgb(swcTypeColor(type));
    const name = document.createElement('span');
    name.textContent = `${type} ${swcTypeName(type)}`;
    const count = document.createElement('span');
    count.className = 'count';
    count.textContent = formatCount(n);
    grid.append(sw, name, count);
  }
  legend.append(grid);
}
