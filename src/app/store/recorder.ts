// A movie of the view (issue 47): one video frame per frame asked for,
// written by the browser's MediaRecorder as WebM (VP8 or VP9, whichever it
// says it supports), in the page, no server. A WebGPU canvas keeps its
// picture only until the task that drew it ends, so each frame is the view
// drawn at once (`ViewCapture.draw`: without overlays, as the screenshot)
// and copied in the same task onto a 2D canvas of the view's size at the
// start, whose capture stream (captureStream(0): frames only when asked)
// gets the frame by requestFrame(). The frames carry the times they were
// asked at: the movie plays at the pace it was recorded.

/** The page's view: its canvas, and drawing it now (not at the next animation frame). */
export interface ViewCapture {
  canvas: HTMLCanvasElement;
  draw(): void;
}

/** WebM types in order of preference (VP8: the cheapest to encode and decoded everywhere). */
const WEBM_TYPES = ['video/webm;codecs=vp8', 'video/webm;codecs=vp9', 'video/webm'];

/** Bits per second asked of the encoder: a sharp picture of a surface at any canvas size. */
const BITS_PER_SECOND = 8_000_000;

/** The WebM type this browser's MediaRecorder writes (null: none). */
export function webmType(): string | null {
  if (typeof MediaRecorder === 'undefined') return null;
  return WEBM_TYPES.find((t) => MediaRecorder.isTypeSupported(t)) ?? null;
}

/** Why the view cannot be recorded here (null: it can). */
export function cannotRecord(capture: ViewCapture | null): string | null {
  if (typeof MediaRecorder === 'undefined') return 'This browser cannot record a movie (no MediaRecorder).';
  if (!webmType()) return 'This browser cannot record a WebM movie (its MediaRecorder writes neither VP8 nor VP9 WebM).';
  if (typeof HTMLCanvasElement.prototype.captureStream !== 'function')
    return 'This browser cannot record a movie (no canvas capture stream).';
  if (!capture) return 'The view cannot be recorded (no view to capture).';
  return null;
}

/** The next animation frame. */
const nextFrame = () => new Promise<void>((resolve) => requestAnimationFrame(() => resolve()));

export class MovieRecorder {
  readonly mimeType: string;
  readonly width: number;
  readonly height: number;
  /** Frames asked for so far. */
  frames = 0;
  readonly #capture: ViewCapture;
  readonly #copy: HTMLCanvasElement;
  readonly #g: CanvasRenderingContext2D;
  readonly #stream: MediaStream;
  readonly #track: CanvasCaptureMediaStreamTrack;
  readonly #recorder: MediaRecorder;
  #chunks: Blob[] = [];
  #ended = false;
  #cancelled = false;
  readonly #stopped: Promise<void>;
  #error: string | null = null;

  /** Starts recording the view at its size now (throws with the browser's message when it cannot). */
  constructor(capture: ViewCapture, mimeType: string) {
    this.#capture = capture;
    // even sizes: what VP8/VP9 encoders ask for
    this.width = Math.max(2, capture.canvas.width & ~1);
    this.height = Math.max(2, capture.canvas.height & ~1);
    const copy = document.createElement('canvas');
    copy.width = this.width;
    copy.height = this.height;
    const g = copy.getContext('2d', { alpha: false });
    if (!g) throw new Error('no 2D canvas to copy the view to');
    this.#copy = copy;
    this.#g = g;
    this.#stream = copy.captureStream(0);
    this.#track = this.#stream.getVideoTracks()[0] as CanvasCaptureMediaStreamTrack;
    this.#recorder = new MediaRecorder(this.#stream, { mimeType, videoBitsPerSecond: BITS_PER_SECOND });
    this.mimeType = this.#recorder.mimeType || mimeType;
    this.#recorder.addEventListener('dataavailable', (e) => {
      if (e.data.size > 0 && !this.#cancelled) this.#chunks.push(e.data);
    });
    this.#stopped = new Promise((resolve) => {
      this.#recorder.addEventListener('stop', () => resolve());
      this.#recorder.addEventListener('error', (e) => {
        this.#error = (e as ErrorEvent).message || 'the recorder failed';
        resolve();
      });
    });
    this.#recorder.start();
  }

  /**
   * One frame: the view as it is now. Resolves once the capture stream has
   * taken it (the next rendering of the page), so frames never merge.
   */
  async frame(): Promise<void> {
    if (this.#ended) return;
    this.#capture.draw();
    // the same task as the draw: the WebGPU canvas still holds its picture
    this.#g.drawImage(this.#capture.canvas, 0, 0, this.width, this.height);
    this.#track.requestFrame();
    this.frames++;
    await nextFrame();
    await nextFrame();
  }

  /** Ends the recording: the WebM file (throws when the recorder failed or wrote nothing). */
  async finish(): Promise<Blob> {
    if (this.#ended) throw new Error('the recording has ended');
    this.#ended = true;
    // the last frame through the encoder before it stops
    await new Promise((resolve) => setTimeout(resolve, 250));
    this.#recorder.stop();
    await this.#stopped;
    this.#release();
    if (this.#error) throw new Error(this.#error);
    const blob = new Blob(this.#chunks, { type: this.mimeType });
    this.#chunks = [];
    if (blob.size === 0) throw new Error('the recorder wrote nothing');
    return blob;
  }

  /** Ends the recording and drops what it wrote. */
  cancel(): void {
    if (this.#ended) return;
    this.#ended = true;
    this.#cancelled = true;
    if (this.#recorder.state !== 'inactive') this.#recorder.stop();
    this.#chunks = [];
    this.#release();
  }

  #release(): void {
    for (const t of this.#stream.getTracks()) t.stop();
    this.#copy.width = this.#copy.height = 0;
  }
}

/** The movie's file name: the store's (its last path part without .zarr / .ozx / .zip) and the time points, e.g. "series-t0-5.webm". */
export function movieFileName(store: string | undefined, from: number, to: number): string {
  const last =
    (store ?? '')
      .replace(/[?#].*$/, '')
      .split('/')
      .filter((p) => p.length > 0)
      .pop() ?? '';
  const base = last.replace(/\.(zarr|ozx|zip)$/i, '').replace(/[^\w.-]+/g, '_') || 'store';
  return `${base}-t${from}-${to}.webm`;
}
