// User-visible messages over the view: errors (bad files, GPU failures) and
// notices. Each can be dismissed; errors stay until then.

export type MessageKind = 'error' | 'info';

export class Messages {
  constructor(private readonly container: HTMLElement) {}

  show(text: string, kind: MessageKind = 'error', timeoutMs?: number): HTMLElement {
    const el = document.createElement('div');
    el.className = `message ${kind}`;
    el.dataset.kind = kind;
    el.textContent = text;
    const close = document.createElement('button');
    close.type = 'button';
    close.textContent = '×';
    close.title = 'Dismiss';
    close.addEventListener('click', () => el.remove());
    el.append(close);
    this.container.append(el);
    if (timeoutMs) setTimeout(() => el.remove(), timeoutMs);
    return el;
  }

  clear(): void {
    this.container.replaceChildren();
  }
}

/** Replaces the whole view with a message (no WebGPU, lost device). */
export function showFatal(stage: HTMLElement, text: string): void {
  const el = document.createElement('div');
  el.className = 'fatal message';
  el.id = 'fatal';
  el.textContent = text;
  stage.append(el);
  document.body.dataset.status = 'error';
}
