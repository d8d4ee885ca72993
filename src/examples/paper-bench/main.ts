// The paper's comparison benchmarks in the browser (paper-bench.html): serial
// marching cubes in JavaScript and WebAssembly, the naive data-parallel
// marching cubes in WebGPU, and zfp decompression with zfp's C decoder in
// WebAssembly and with our WebGPU decoder, on a shared volume or a file. The
// same measurement code as `npm run bench:paper` (measure.ts, gpu-measure.ts),
// which drives this page headless through `window.paperBench` for the
// "in Chromium" columns of its report.
import { Messages } from '../../app/messages.ts';
import { describeAdapter, requestGpu, type GpuContext } from '../../gpu/device.ts';
import { compressOnGpu } from '../../volume/open-volume.ts';
import type { Dims3 } from '../../mc/serial-mc.ts';
import { isovalueSequence } from '../../bench/sequences.ts';
import { summarize } from '../../bench/stats.ts';
import { DTYPE_BYTES, type DType } from '../../core/dtype.ts';
import { parseVolumeName } from '../../core/naming.ts';
import { ZfpDecoder } from '../../zfp/decoder.ts';
import { loadZfpStream } from '../../zfp/gpu-stream.ts';
import { ZfpWasmStream } from '../../loaders/zfp-wasm.ts';
import { byId, formatBytes } from '../common.ts';
import { timeGpuDecode, timeNaiveMc } from './gpu-measure.ts';
import { interestingRange, meanAfterFirst, timeSerialMc, timeZfpWasm, type SerialMethod, type SerialTimes } from './measure.ts';

/** What `npm run bench:paper` calls through Playwright. */
export interface PaperBenchApi {
  version: 1;
  info(): { userAgent: string; hardwareConcurrency: number; webgpu: boolean };
  serialMc(req: {
    url: string;
    dims: Dims3;
    isovalues: number[];
    methods: SerialMethod[];
  }): Promise<Partial<Record<SerialMethod, SerialTimes>>>;
  zfpWasm(req: { url: string; runs: number }): Promise<{ ms: number[]; dims: Dims3; floatBytes: number; sample: number[] }>;
  gpuDecode(req: { url: string; runs: number }): Promise<{ ms: number[]; timing: string; floatBytes: number; adapter: string }>;
  naiveMc(req: {
    url: string;
    isovalues: number[];
    vertexCapacity?: number;
  }): Promise<{ ms: number[]; triangles: number[]; timing: string; adapter: string }>;
}

declare global {
  interface Window {
    paperBench?: PaperBenchApi;
  }
}

const PRESETS: { label: string; url: string }[] = [
  { label: 'fuel 64³ (float32 raw)', url: '/data/volumes/fuel_64x64x64_float32.raw' },
  { label: 'hydrogen atom 128³ (zfp rate 8)', url: '/data/volumes/hydrogen_atom_128x128x128_float32.rate8.zfp' },
  { label: 'bonsai 256³ (zfp rate 4)', url: '/data/volumes/bonsai_256x256x256_float32.rate4.zfp' },
];

const messages = new Messages(byId('messages'));
const status = byId<HTMLSpanElement>('status');
const runButton = byId<HTMLButtonElement>('run');
let gpuPromise: Promise<GpuContext> | undefined;

function gpu(): Promise<GpuContext> {
  gpuPromise ??= requestGpu(navigator.gpu, {
    label: 'paperBench.device',
    onFailure: (f) => messages.show(`WebGPU ${f.kind}: ${f.message}`),
  }).catch((e: unknown) => {
    gpuPromise = undefined;
    throw e;
  });
  return gpuPromise;
}

async function fetchBytes(url: string): Promise<Uint8Array> {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return new Uint8Array(await r.arrayBuffer());
}

const api: PaperBenchApi = {
  version: 1,
  info: () => ({ userAgent: navigator.userAgent, hardwareConcurrency: navigator.hardwareConcurrency, webgpu: 'gpu' in navigator }),
  async serialMc({ url, dims, isovalues, methods }) {
    const bytes = await fetchBytes(url);
    const values = new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
    if (values.length !== dims[0] * dims[1] * dims[2])
      throw new Error(`${url}: ${values.length} floats, ${dims.join('x')} needs ${dims[0] * dims[1] * dims[2]}`);
    return timeSerialMc(values, dims, isovalues, methods);
  },
  async zfpWasm({ url, runs }) {
    return timeZfpWasm(await fetchBytes(url), runs, url);
  },
  async gpuDecode({ url, runs }) {
    const g = await gpu();
    const stream = loadZfpStream(g.device, await fetchBytes(url), url.split('/').pop()!);
    const decoder = await ZfpDecoder.create(g.device);
    try {
      const t = await timeGpuDecode(g.device, decoder, stream, runs);
      return { ...t, adapter: describeAdapter(g.adapter) };
    } finally {
      decoder.destroy();
      stream.destroy();
    }
  },
  async naiveMc({ url, isovalues, vertexCapacity }) {
    const g = await gpu();
    const stream = loadZfpStream(g.device, await fetchBytes(url), url.split('/').pop()!);
    const decoder = await ZfpDecoder.create(g.device);
    try {
      const t = await timeNaiveMc(g.device, decoder, stream, isovalues, { vertexCapacity });
      return {
        ms: t.results.map((r) => r.gpuMs),
        triangles: t.results.map((r) => r.triangles),
        timing: t.results[0]?.timing ?? 'none',
        adapter: describeAdapter(g.adapter),
      };
    } finally {
      decoder.destroy();
      stream.destroy();
    }
  },
};
window.paperBench = api;

// ---------------------------------------------------------------- the form

interface LoadedVolume {
  name: string;
  dims: Dims3;
  /** The field every method contours (the zfp stream's decode). */
  values: Float32Array;
  /** zfp fixed-rate with header (given, or made on the GPU from a raw file). */
  zfp: Uint8Array;
}

async function loadVolume(name: string, bytes: Uint8Array): Promise<LoadedVolume> {
  if (bytes[0] === 0x7a && bytes[1] === 0x66 && bytes[2] === 0x70) {
    const s = await ZfpWasmStream.load(bytes, name);
    try {
      s.decode();
      return { name, dims: s.info.dims, values: s.output().slice(), zfp: bytes };
    } finally {
      s.free();
    }
  }
  const facts = parseVolumeName(name);
  if (!facts.dims || !facts.dtype) throw new Error(`${name}: give a zfp file with header or a raw volume named name_XxYxZ_dtype.raw`);
  const dtype: DType = facts.dtype;
  const [x, y, z] = facts.dims;
  if (bytes.byteLength !== x * y * z * DTYPE_BYTES[dtype])
    throw new Error(`${name}: ${x}x${y}x${z} ${dtype} needs ${x * y * z * DTYPE_BYTES[dtype]} bytes, the file has ${bytes.byteLength}`);
  const g = await gpu();
  const stream = await compressOnGpu(g.device, bytes, dtype, facts.dims, 8, name);
  try {
    const zfp = await stream.readBytes();
    return loadVolume(name.replace(/\.raw$/, '.rate8.zfp'), zfp);
  } finally {
    stream.destroy();
  }
}

function row(cells: (string | number)[]): HTMLTableRowElement {
  const tr = document.createElement('tr');
  for (const c of cells) {
    const td = document.createElement('td');
    td.textContent = typeof c === 'number' ? (Number.isInteger(c) ? c.toLocaleString('en-US') : c.toFixed(2)) : c;
    tr.append(td);
  }
  return tr;
}

async function runForm(): Promise<void> {
  const file = byId<HTMLInputElement>('file-input').files?.[0];
  const preset = byId<HTMLSelectElement>('volume').value;
  const count = Math.max(2, Math.floor(Number(byId<HTMLInputElement>('count').value) || 20));
  const runs = Math.max(2, Math.floor(Number(byId<HTMLInputElement>('runs').value) || 10));
  const methods = [...document.querySelectorAll<HTMLInputElement>('input[name=method]:checked')].map((i) => i.value);
  const body = byId<HTMLTableElement>('results').tBodies[0];
  body.replaceChildren();
  status.textContent = 'loading the volume…';
  const name = file ? file.name : preset.split('/').pop()!;
  const v = await loadVolume(name, file ? new Uint8Array(await file.arrayBuffer()) : await fetchBytes(preset));
  const typed = byId<HTMLInputElement>('range').value.split(',').map(Number);
  const range: [number, number] = typed.length === 2 && typed[0] < typed[1] ? [typed[0], typed[1]] : interestingRange(v.values, v.dims);
  const isovalues = isovalueSequence('random', count, range, 1);
  byId('results-note').textContent =
    `${v.name} (${v.dims.join('×')}): ${count} seeded random isovalues in [${range[0].toFixed(2)}, ${range[1].toFixed(2)}]; ` +
    'the first run of each method is left out (warm-up), as in the paper.';
  const show = (label: string, ms: number[], triangles?: number[], throughput?: string) => {
    const s = summarize(ms);
    body.append(
      row([
        label,
        `${s.mean.toFixed(2)} ms`,
        `${s.median.toFixed(2)} ms`,
        s.samples.length,
        triangles ? Math.round(meanAfterFirst(triangles)) : '',
        throughput ?? '',
      ]),
    );
  };
  const serial = methods.filter((m): m is SerialMethod => m === 'js' || m === 'wasm');
  if (serial.length) {
    status.textContent = 'serial marching cubes…';
    const t = await timeSerialMc(v.values, v.dims, isovalues, serial, (d, n) => (status.textContent = `serial marching cubes ${d}/${n}…`));
    for (const m of serial) show(m === 'js' ? 'serial MC, JavaScript' : 'serial MC, WebAssembly', t[m]!.ms, t[m]!.triangles);
  }
  const mbps = (bytes: number, ms: number[]) => `${(bytes / 1e6 / (meanAfterFirst(ms) / 1000)).toFixed(0)} MB/s`;
  if (methods.includes('zfp-wasm')) {
    status.textContent = 'zfp decode (Wasm)…';
    const t = await timeZfpWasm(v.zfp, runs, v.name);
    show("zfp decode, zfp's C in Wasm", t.ms, undefined, mbps(t.floatBytes, t.ms));
  }
  if (methods.includes('zfp-webgpu') || methods.includes('naive')) {
    const g = await gpu();
    const stream = loadZfpStream(g.device, v.zfp, v.name);
    const decoder = await ZfpDecoder.create(g.device);
    try {
      if (methods.includes('zfp-webgpu')) {
        status.textContent = 'zfp decode (WebGPU)…';
        const t = await timeGpuDecode(g.device, decoder, stream, runs);
        show(`zfp decode, WebGPU (${t.timing})`, t.ms, undefined, mbps(t.floatBytes, t.ms));
      }
      if (methods.includes('naive')) {
        const t = await timeNaiveMc(g.device, decoder, stream, isovalues, {
          onProgress: (d, n) => (status.textContent = `naive WebGPU marching cubes ${d}/${n}…`),
        });
        show(
          `naive MC, WebGPU (${t.results[0]?.timing})`,
          t.results.map((r) => r.gpuMs),
          t.results.map((r) => r.triangles),
        );
        body.append(
          row(['naive MC, GPU memory (volume + per-cell buffers + soup)', formatBytes(t.volumeBytes + t.workingBytes), '', '', '', '']),
        );
      }
    } finally {
      decoder.destroy();
      stream.destroy();
    }
  }
  status.textContent = 'done';
}

function setUp(): void {
  const select = byId<HTMLSelectElement>('volume');
  for (const p of PRESETS) select.append(new Option(p.label, p.url));
  // A chosen file replaces the preset (clearing the file brings the preset back).
  const fileInput = byId<HTMLInputElement>('file-input');
  fileInput.addEventListener('change', () => (select.disabled = (fileInput.files?.length ?? 0) > 0));
  byId<HTMLFormElement>('form').addEventListener('submit', (e) => {
    e.preventDefault();
    runButton.disabled = true;
    runForm()
      .catch((err: unknown) => {
        messages.show((err as Error).message ?? String(err));
        status.textContent = 'failed';
      })
      .finally(() => (runButton.disabled = false));
  });
  runButton.disabled = false;
  status.textContent = 'ready';
  document.body.dataset.status = 'ready';
  if ('gpu' in navigator) {
    gpu()
      .then((g) => {
        byId('gpu-info').replaceChildren(
          ...[
            ['adapter', describeAdapter(g.adapter)],
            ['CPU threads', String(navigator.hardwareConcurrency)],
          ].flatMap(([k, v]) => {
            const dt = document.createElement('dt');
            dt.textContent = k;
            const dd = document.createElement('dd');
            dd.textContent = v;
            return [dt, dd];
          }),
        );
      })
      .catch((e: unknown) =>
        messages.show(`No WebGPU here (${(e as Error).message}); the serial and Wasm measurements still run.`, 'info'),
      );
  }
}

setUp();
