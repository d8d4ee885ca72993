// Page-wide input: files dropped on the page or picked, the view toolbar,
// display options and keyboard shortcuts that work wherever the focus is
// (outside text fields).

import { isTyping } from './dom.ts';

export interface ControlActions {
  openFiles: (files: File[]) => void;
  loadDefault: () => void;
  resetView: () => void;
  fitView: () => void;
  savePng: () => void;
  savePly: () => void;
  saveGlb: () => void;
  copyLink: () => void;
  stepIso: (steps: number) => void;
  /** Moves the clip plane along its normal (, and .). */
  stepClipPlane: (steps: number) => void;
  setBoxVisible: (on: boolean) => void;
  setSmooth: (on: boolean) => void;
  setColors: (front: string, back: string) => void;
  setUpAxis: (up: 'x' | 'y' | 'z') => void;
  /** Escape: stop a load in progress (the current volume stays). */
  cancelLoad: () => void;
}

/** Files dragged anywhere over the page are dropped on the view. */
export function acceptDrops(overlay: HTMLElement, onFiles: (files: File[]) => void): void {
  let depth = 0;
  const hasFiles = (e: DragEvent) => [...(e.dataTransfer?.types ?? [])].includes('Files');
  window.addEventListener('dragenter', (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    depth++;
    overlay.hidden = false;
  });
  window.addEventListener('dragover', (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    if (e.dataTransfer) e.dataTransfer.dropEffect = 'copy';
  });
  window.addEventListener('dragleave', () => {
    depth = Math.max(0, depth - 1);
    if (depth === 0) overlay.hidden = true;
  });
  window.addEventListener('drop', (e) => {
    e.preventDefault();
    depth = 0;
    overlay.hidden = true;
    const files = [...(e.dataTransfer?.files ?? [])];
    if (files.length > 0) onFiles(files);
  });
}

export function wireControls(a: ControlActions): void {
  const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;
  const input = $<HTMLInputElement>('file-input');
  input.addEventListener('change', () => {
    const files = [...(input.files ?? [])];
    input.value = '';
    if (files.length > 0) a.openFiles(files);
  });
  // The label acts as the button: Enter/Space open the picker too.
  $('open-file').addEventListener('keydown', (e) => {
    if (e.key === 'Enter' || e.key === ' ') {
      e.preventDefault();
      input.click();
    }
  });
  $('load-default').addEventListener('click', a.loadDefault);
  $('reset-view').addEventListener('click', a.resetView);
  $('fit-view').addEventListener('click', a.fitView);
  $('save-png').addEventListener('click', a.savePng);
  $('save-ply').addEventListener('click', a.savePly);
  $('save-glb').addEventListener('click', a.saveGlb);
  $('copy-link').addEventListener('click', a.copyLink);
  const box = $<HTMLInputElement>('show-box');
  box.addEventListener('change', () => a.setBoxVisible(box.checked));
  const smooth = $<HTMLInputElement>('smooth-normals');
  smooth.addEventListener('change', () => a.setSmooth(smooth.checked));
  const front = $<HTMLInputElement>('front-color');
  const back = $<HTMLInputElement>('back-color');
  const colors = () => a.setColors(front.value, back.value);
  front.addEventListener('input', colors);
  const up = $<HTMLSelectElement>('up-axis');
  up.addEventListener('change', () => a.setUpAxis(up.value as 'x' | 'y' | 'z'));
  back.addEventListener('input', colors);

  document.addEventListener('keydown', (e) => {
    if (e.defaultPrevented || e.ctrlKey || e.metaKey || e.altKey || isTyping(e.target)) return;
    if (document.querySelector('dialog[open]')) return;
    if (e.key === 'Escape') {
      a.cancelLoad();
      return;
    }
    // The canvas handles its own keys (R, F, +, -) when focused.
    const onCanvas = e.target instanceof HTMLCanvasElement;
    switch (e.key) {
      case ',':
      case '<':
        a.stepClipPlane(e.shiftKey ? -10 : -1);
        break;
      case '.':
      case '>':
        a.stepClipPlane(e.shiftKey ? 10 : 1);
        break;
      case '[':
      case '{':
        a.stepIso(e.shiftKey ? -10 : -1);
        break;
      case ']':
      case '}':
        a.stepIso(e.shiftKey ? 10 : 1);
        break;
      case 'p':
      case 'P':
        a.savePng();
        break;
      case 'r':
      case 'R':
        if (onCanvas) return;
        a.resetView();
        break;
      case 'f':
      case 'F':
        if (onCanvas) return;
        a.fitView();
        break;
      default:
        return;
    }
    e.preventDefault();
  });
}

/** '#rrggbb' -> [r, g, b] in 0..1 */
export function hexToRgb(hex: string): [number, number, number] {
  const n = Number.parseInt(hex.replace('#', ''), 16);
  return [((n >> 16) & 255) / 255, ((n >> 8) & 255) / 255, (n & 255) / 255];
}
