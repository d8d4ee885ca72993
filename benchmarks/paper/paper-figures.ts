// The paper's published figures (Usher & Pascucci, LDAV 2020; LaTeX source
// in ../shared/reference/paper.tex), as published on their hardware: a
// Surface Pro 7 (i5-1035G4 CPU, integrated GPU with 3.8 GB VRAM) and a desktop
// with an RTX 2070, Chrome Canary / Firefox Nightly of 2020. Each table row
// keeps the LaTeX it was read from; `checkAgainstPaper` confirms every one
// still appears verbatim in paper.tex when the file is present.
import { existsSync, readFileSync } from 'node:fs';

export interface NaiveRow {
  dataset: string;
  surfacePro7: { vulkanMs: number; webgpuMs: number | null };
  rtx2070: { vulkanMs: number; webgpuMs: number };
  latex: [string, string];
}

/** Table 2 (tab:mc_naive_parallel_perf): naive data-parallel MC, mean ms over 100 random isovalues. */
export const NAIVE_MC: NaiveRow[] = [
  {
    dataset: 'Fuel',
    surfacePro7: { vulkanMs: 25, webgpuMs: 26 },
    rtx2070: { vulkanMs: 2, webgpuMs: 18 },
    latex: ['Fuel $64^3$ & 25ms & 26ms', 'Fuel $64^3$ & 2ms & 18ms'],
  },
  {
    dataset: 'Hydr.',
    surfacePro7: { vulkanMs: 58, webgpuMs: 86 },
    rtx2070: { vulkanMs: 8, webgpuMs: 18 },
    latex: ['Hydr. $128^3$ & 58ms & 86ms', 'Hydr. $128^3$ & 8ms & 18ms'],
  },
  {
    dataset: 'Bonsai',
    surfacePro7: { vulkanMs: 228, webgpuMs: 261 },
    rtx2070: { vulkanMs: 49, webgpuMs: 49 },
    latex: ['Bonsai $256^3$ & 228ms & 261ms', 'Bonsai $256^3$ & 49ms & 49ms'],
  },
  {
    dataset: 'Skull',
    surfacePro7: { vulkanMs: 279, webgpuMs: 282 },
    rtx2070: { vulkanMs: 70, webgpuMs: 50 },
    latex: ['Skull $256^3$ & 279ms & 282ms', 'Skull $256^3$ & 70ms & 50ms'],
  },
  {
    dataset: 'Plasma',
    surfacePro7: { vulkanMs: 1357, webgpuMs: null },
    rtx2070: { vulkanMs: 322, webgpuMs: 329 },
    latex: ['Plasma $512^3$ & 1357ms & $*$', 'Plasma $512^3$ & 322ms & 329ms'],
  },
];

export interface ZfpRow {
  dataset: string;
  machine: 'Surface Pro 7' | 'RTX 2070';
  /** MB/s on the Surface Pro 7 (serial CPU, Vulkan, WebGPU); GB/s on the RTX 2070 (CUDA, Vulkan, WebGPU). */
  columns: Record<string, string>;
  latex: string;
}

/** Table 3 (tab:zfp_decompress): ZFP decompression, mean of 10 runs over rates 2, 4 and 8. */
export const ZFP: ZfpRow[] = [
  {
    dataset: 'Skull 256³',
    machine: 'Surface Pro 7',
    columns: { 'CPU (serial)': '329 MB/s', Vulkan: '756 MB/s', WebGPU: '697 MB/s' },
    latex: 'Skull $256^3$ & 329MB/s & 756MB/s & 697MB/s',
  },
  {
    dataset: 'Plasma 512³',
    machine: 'Surface Pro 7',
    columns: { 'CPU (serial)': '349 MB/s', Vulkan: '898 MB/s', WebGPU: '777 MB/s' },
    latex: 'Plasma $512^3$ & 349MB/s & 898MB/s & 777MB/s',
  },
  {
    dataset: 'Skull 256³',
    machine: 'RTX 2070',
    columns: { CUDA: '67.1 GB/s', Vulkan: '14.8 GB/s', WebGPU: '7.6 GB/s' },
    latex: 'Skull $256^3$ & 67.1GB/s & 14.8GB/s & 7.6GB/s',
  },
  {
    dataset: 'Plasma 512³',
    machine: 'RTX 2070',
    columns: { CUDA: '67.8 GB/s', Vulkan: '19.4 GB/s', WebGPU: '11.8 GB/s' },
    latex: 'Plasma $512^3$ & 67.8GB/s & 19.4GB/s & 11.8GB/s',
  },
  {
    dataset: 'Miranda 1024³',
    machine: 'RTX 2070',
    columns: { CUDA: '113 GB/s', Vulkan: '19.6 GB/s', WebGPU: '13.7 GB/s' },
    latex: 'Miranda $1024^3$ & 113GB/s & 19.6GB/s & 13.7GB/s',
  },
];

export interface BlockRow {
  dataset: string;
  /** hit rate %, RTX 2070 ms, Surface Pro 7 ms (null: out of memory). */
  random: [number, number, number | null];
  sweepUp: [number, number, number | null];
  sweepDown: [number, number, number | null];
  latex: string;
}

/** Table 5 (tab:mc_benchmark_table): block-compressed isosurfaces, 100 isovalues per benchmark. */
export const BLOCK: BlockRow[] = [
  {
    dataset: 'Skull 256³',
    random: [98.4, 57.7, 99.8],
    sweepUp: [100, 54.4, 85.1],
    sweepDown: [94.8, 93.1, 161.5],
    latex: 'Skull & 98.4\\% & 57.7ms & 99.8ms & 100\\% & 54.4ms & 85.1ms & 94.8\\% & 93.1ms & 161.5ms',
  },
  {
    dataset: 'Foot 256³',
    random: [98.9, 57.1, 107.9],
    sweepUp: [100, 58.4, 99.2],
    sweepDown: [97.4, 90.1, 164.4],
    latex: 'Foot & 98.9\\% & 57.1ms & 107.9ms & 100\\% & 58.4ms & 99.2ms & 97.4\\% & 90.1ms & 164.4ms',
  },
  {
    dataset: 'Backpack 512×512×373',
    random: [99.4, 68.1, 251.0],
    sweepUp: [100, 99.1, 216.3],
    sweepDown: [96.8, 109.7, 349.3],
    latex: 'Backpack & 99.4\\% & 68.1ms & 251.0ms & 100\\% & 99.1ms & 216.3ms & 96.8\\% & 109.7ms & 349.3ms',
  },
  {
    dataset: 'Plasma 512³',
    random: [96.4, 107.2, 318.6],
    sweepUp: [99.8, 94.3, 265.3],
    sweepDown: [98.5, 126.1, 431.8],
    latex: 'Plasma & 96.4\\% & 107.2ms & 318.6ms & 99.8\\% & 94.3ms & 265.3ms & 98.5\\% & 126.1ms & 431.8ms',
  },
  {
    dataset: 'Stag Beetle 832×832×494',
    random: [98.2, 123.1, 322.1],
    sweepUp: [99.6, 125.1, 337.8],
    sweepDown: [92.0, 151.2, 464.5],
    latex: 'Stag Beetle & 98.2\\% & 123.1ms & 322.1ms & 99.6\\% & 125.1ms & 337.8ms & 92.0\\% & 151.2ms & 464.5ms',
  },
  {
    dataset: 'Kingsnake 1024×1024×795',
    random: [99.2, 212.6, 926.5],
    sweepUp: [100, 185.3, 811.1],
    sweepDown: [97.0, 284.5, 1306],
    latex: 'Kingsnake & 99.2\\% & 212.6ms & 926.5ms & 100\\% & 185.3ms & 811.1ms & 97.0\\% & 284.5ms & 1306ms',
  },
  {
    dataset: 'Chameleon 1024×1024×1080',
    random: [90.9, 371.6, 1342],
    sweepUp: [98.9, 348.7, 1470],
    sweepDown: [96.6, 337.1, 1482],
    latex: 'Chameleon & 90.9\\% & 371.6ms & 1342ms & 98.9\\% & 348.7ms & 1470ms & 96.6\\% & 337.1ms & 1482ms',
  },
  {
    dataset: 'Miranda 1024³',
    random: [46.8, 2218, null],
    sweepUp: [95.7, 550.5, null],
    sweepDown: [95.2, 549.6, null],
    latex: 'Miranda & 46.8\\% & 2218ms & (oom) & 95.7\\% & 550.5ms & (oom) & 95.2\\% & 549.6ms & (oom)',
  },
  {
    dataset: 'DNS 10240×7680×1536',
    random: [62.9, 2632, null],
    sweepUp: [98.4, 972, null],
    sweepDown: [97.9, 841.3, null],
    latex: 'DNS & 62.9\\% & 2632ms & (oom) & 98.4\\% & 972ms & (oom) & 97.9\\% & 841.3ms & (oom)',
  },
];

/** Section 3.3.3, on its Figure 6 (no table): serial MC on the Surface Pro 7, 100 random isovalues, slowdowns vs native C++. */
export const SERIAL_MC = {
  firefox: { wasmVsNative: 1.5, jsVsNative: 4.4 },
  chrome: { wasmVsNative: 3.2, jsVsNative: 3.6 },
  latex: [
    'is on average only 1.5$\\times$ slower than native code',
    "Firefox's JavaScript engine is on average 4.4$\\times$ slower than native code",
    'averaging 3.2$\\times$ and 3.6$\\times$ slower than native code, respectively',
  ],
};

/** Every LaTeX fragment above that is missing from paper.tex (empty: all found), or null without the file. */
export function checkAgainstPaper(paperTex: string): string[] | null {
  if (!existsSync(paperTex)) return null;
  const text = readFileSync(paperTex, 'utf8').replace(/\s+/g, ' ');
  const fragments = [...NAIVE_MC.flatMap((r) => r.latex), ...ZFP.map((r) => r.latex), ...BLOCK.map((r) => r.latex), ...SERIAL_MC.latex];
  return fragments.filter((f) => !text.includes(f));
}
