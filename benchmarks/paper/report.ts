// The Markdown report of `npm run bench:paper`: one table per paper table,
// our figures beside the paper's published ones (on their hardware), the
// headline ratios, and what was chosen and why.
import { meanAfterFirst } from '../../src/examples/paper-bench/measure.ts';
import { BLOCK, NAIVE_MC, SERIAL_MC, ZFP } from './paper-figures.ts';
import type { PaperBenchResult } from './result.ts';

const f1 = (x: number | undefined | null, digits = 1) => (x === undefined || x === null || !Number.isFinite(x) ? '–' : x.toFixed(digits));
const ms = (x: number | undefined | null) =>
  x === undefined || x === null || !Number.isFinite(x) ? '–' : x >= 100 ? x.toFixed(0) : x >= 10 ? x.toFixed(1) : x.toFixed(2);
const ratio = (x: number | undefined | null) =>
  x === undefined || x === null || !Number.isFinite(x) ? '–' : `${x >= 10 ? x.toFixed(0) : x.toFixed(2)}×`;
const pct = (x: number | undefined) => (x === undefined || !Number.isFinite(x) ? '–' : `${(100 * x).toFixed(1)}%`);
const mib = (b: number) => `${(b / 2 ** 20).toFixed(b >= 100 * 2 ** 20 ? 0 : 1)} MiB`;
const minutes = (s: number) => (s >= 90 ? `${(s / 60).toFixed(1)} min` : `${s.toFixed(0)} s`);

function table(header: string[], rows: (string | number)[][], align?: ('l' | 'r')[]): string {
  const a = align ?? header.map((_, i) => (i === 0 ? 'l' : 'r'));
  const lines = [`| ${header.join(' | ')} |`, `|${a.map((x) => (x === 'l' ? ':---' : '---:')).join('|')}|`];
  for (const r of rows) lines.push(`| ${r.map(String).join(' | ')} |`);
  return lines.join('\n');
}

export function writeReport(r: PaperBenchResult): string {
  const out: string[] = [];
  const software = r.adapter.software;
  const gpuWord = software ? 'SwiftShader (a CPU emulating a GPU)' : r.adapterDescription;
  out.push(`# The paper's comparison benchmarks: ${r.date.slice(0, 10)}, ${r.adapterSlug}${r.mode === 'quick' ? ' (quick)' : ''}`);
  out.push('');
  out.push(
    `Usher & Pascucci, "Interactive Visualization of Terascale Data in the Browser: Fact or Fiction?" (LDAV 2020), reproduced by \`${r.command}\`. ` +
      `Our figures were measured on **${r.machine.cpu}** (${r.machine.cores} cores, ${r.machine.memoryGiB} GiB) with WebGPU on **${gpuWord}**; ` +
      "the paper's figures are **as published on their hardware** (a Surface Pro 7: i5-1035G4 CPU with an integrated GPU; a desktop with an RTX 2070), quoted from `../shared/reference/paper.tex`." +
      (software
        ? ' On SwiftShader every "GPU" number below is CPU work through a Vulkan emulator, so GPU-vs-CPU ratios here say nothing about GPUs; the ratios between methods on the same device (naive vs block-compressed) and the CPU-side ratios (Wasm vs native vs JS) are the meaningful ones.'
        : ''),
  );
  out.push('');
  const limit = r.limits.seconds;
  out.push(
    table(
      ['', ''],
      [
        ['run', `${r.mode} (\`${r.command}\`)`],
        [
          'duration',
          `${minutes(r.durations.totalSeconds)} (limit ${minutes(limit)}${r.durations.totalSeconds > limit ? ', **exceeded**' : ''}); ${Object.entries(
            r.durations.sections,
          )
            .map(([k, s]) => `${k} ${minutes(s)}`)
            .join(', ')}`,
        ],
        [
          'CPU',
          `${r.machine.cpu}, ${r.machine.cores} cores, ${r.machine.memoryGiB} GiB; load average ${r.machine.loadAverage.start.map((x) => x.toFixed(1)).join(' ')} at the start, ${r.machine.loadAverage.end.map((x) => x.toFixed(1)).join(' ')} at the end`,
        ],
        ['GPU adapter', `${r.adapterDescription}; GPU times: ${r.gpuTiming}`],
        [
          'browser',
          r.chromium.error
            ? `not run: ${r.chromium.error}`
            : `Chromium ${r.chromium.version} (headless, ${r.chromium.flags.join(' ')}); ${r.chromium.hardwareConcurrency} threads`,
        ],
        ['Node', `${r.machine.node} (Dawn \`webgpu\` ${r.machine.dawn})`],
        ['native compiler', r.serialNative.compiler ?? `none: ${r.serialNative.error}`],
        ['seed', String(r.settings.seed)],
      ],
      ['l', 'l'],
    ),
  );
  out.push('');
  if (r.errors.length) {
    out.push('**Errors during the run** (the tables leave these out):');
    out.push('');
    for (const e of r.errors) out.push(`- ${e.section}${e.volume ? ` (${e.volume})` : ''}: ${e.message}`);
    out.push('');
  }

  // ------------------------------------------------------------ headline
  out.push('## Headline ratios');
  out.push('');
  const h = r.headline;
  out.push(
    `- **Serial marching cubes** (mean over volumes of the per-volume ratio of mean ms per surface): Wasm / native ${ratio(h.serial.wasmNodeVsNative)} in Node, ${ratio(h.serial.wasmChromiumVsNative)} in Chromium; JS / native ${ratio(h.serial.jsNodeVsNative)} in Node, ${ratio(h.serial.jsChromiumVsNative)} in Chromium; JS / Wasm ${ratio(h.serial.jsNodeVsWasmNode)} in Node, ${ratio(h.serial.jsChromiumVsWasmChromium)} in Chromium. Paper (Surface Pro 7): Wasm / native ${SERIAL_MC.firefox.wasmVsNative}× in Firefox, ${SERIAL_MC.chrome.wasmVsNative}× in Chrome; JS / native ${SERIAL_MC.firefox.jsVsNative}× in Firefox, ${SERIAL_MC.chrome.jsVsNative}× in Chrome.`,
  );
  out.push(
    `- **Naive WebGPU MC vs block-compressed** (same random isovalues, same device): ${h.naiveVsBlock.map((x) => `${x.label} naive ${ms(x.naiveMs)} ms vs block ${ms(x.blockMs)} ms = ${ratio(x.ratio)}`).join('; ') || '–'}.`,
  );
  out.push(
    `- **Our WebGPU zfp decoder vs zfp's serial C decoder (zfpy)** (MB/s ratio, mean over volumes): ${h.zfp.map((x) => `rate ${x.rate}: ${ratio(x.webgpuVsSerial)}`).join(', ') || '–'}; zfp's C decoder in Wasm vs native: ${h.zfp.map((x) => `rate ${x.rate}: ${ratio(x.wasmNodeVsSerial)} (Node)${x.wasmChromiumVsSerial ? `, ${ratio(x.wasmChromiumVsSerial)} (Chromium)` : ''}`).join(', ') || '–'}. Paper (Surface Pro 7): WebGPU / serial CPU 697/329 = 2.1× (Skull), 777/349 = 2.2× (Plasma).`,
  );
  out.push('');

  out.push(...readingNotes(r));

  // ------------------------------------------------------------ serial
  out.push('## Serial marching cubes: native C++, WebAssembly, JavaScript (paper §3.3.3, Fig. 6)');
  out.push('');
  out.push(
    `One algorithm and one case table (\`src/mc/serial-mc.ts\`, \`benchmarks/serial-mc/serial_mc.cpp\` compiled with g++ -O3 and with Debian's emcc -O3); ` +
      `${r.settings.serialCounts} seeded random isovalues per volume over its range, each surface computed once per method, the first discarded; mean ms per surface. ` +
      'Native times are taken inside the binary; Wasm and JS times include allocating the triangle soup. Every method gave the same triangle count at every isovalue.',
  );
  out.push('');
  out.push(
    table(
      [
        'volume',
        'isovalues',
        'mean triangles',
        'native ms',
        'Wasm Node ms',
        'Wasm Chromium ms',
        'JS Node ms',
        'JS Chromium ms',
        'Wasm/native (Node, Chromium)',
        'JS/native (Node, Chromium)',
      ],
      r.serial.map((s) => [
        s.label,
        s.isovalues.length,
        Math.round(meanAfterFirst(s.jsNode.triangles)),
        ms(s.means.native),
        ms(s.means.wasmNode),
        ms(s.means.wasmChromium),
        ms(s.means.jsNode),
        ms(s.means.jsChromium),
        `${ratio(s.means.wasmNode / s.means.native!)}, ${ratio(s.means.wasmChromium! / s.means.native!)}`,
        `${ratio(s.means.jsNode / s.means.native!)}, ${ratio(s.means.jsChromium! / s.means.native!)}`,
      ]),
    ),
  );
  out.push('');
  out.push(
    `Paper (Surface Pro 7, 100 random isovalues; the figure gives no numbers, the text gives the ratios): Wasm is ${SERIAL_MC.firefox.wasmVsNative}× slower than native in Firefox and ${SERIAL_MC.chrome.wasmVsNative}× in Chrome; JS ${SERIAL_MC.firefox.jsVsNative}× in Firefox and ${SERIAL_MC.chrome.jsVsNative}× in Chrome.`,
  );
  out.push('');

  // ------------------------------------------------------------ naive
  out.push('## Naive data-parallel marching cubes in WebGPU (paper Table 2)');
  out.push('');
  out.push(
    'Over the whole decompressed volume in GPU memory (`src/mc/naive-gpu.ts`): mark active cells, scan, compact their IDs, per-cell vertex counts, scan, emit; ' +
      `every pass after the first dispatched indirectly from GPU counts. GPU time from the first to the last pass (${r.gpuTiming}), one surface per submission; ` +
      "in Node each naive surface is computed right after the block pipeline's surface at the same isovalue during its random mode, so both see the same machine load; " +
      "measured in Node (Dawn, the WebGPU implementation Chrome uses, without the browser) and in Chromium's WebGPU: the analogue of the paper's native Vulkan vs browser WebGPU columns; " +
      'the same isovalues as the serial table (a prefix of them where fewer), first discarded. Triangles equal the serial ones at every isovalue' +
      (r.naive.some((n) => !n.trianglesMatchSerial) ? ' **except where marked**' : '') +
      '.',
  );
  out.push('');
  out.push(
    table(
      [
        'volume',
        'surfaces',
        'mean triangles',
        `ours, Dawn in Node (${software ? 'SwiftShader' : 'GPU'}) ms`,
        ...(r.naive.some((n) => n.chromiumMs) ? ["ours, Chromium's WebGPU ms"] : []),
        'serial native ms (same isovalues)',
        'GPU memory (volume + per-cell + soup)',
        'paper Surface Pro 7 Vulkan / WebGPU',
        'paper RTX 2070 Vulkan / WebGPU',
      ],
      r.naive.map((n) => {
        const p = NAIVE_MC.find((x) => x.dataset === n.paperName);
        return [
          n.label,
          n.ms.length,
          Math.round(meanAfterFirst(n.triangles)) + (n.trianglesMatchSerial ? '' : ' (≠ serial)'),
          ms(meanAfterFirst(n.ms)),
          ...(r.naive.some((x) => x.chromiumMs) ? [ms(n.chromiumMs ? meanAfterFirst(n.chromiumMs) : undefined)] : []),
          ms(n.serialNativeMs),
          mib(n.memoryBytes),
          p ? `${p.surfacePro7.vulkanMs} / ${p.surfacePro7.webgpuMs ?? 'failed'} ms` : '–',
          p ? `${p.rtx2070.vulkanMs} / ${p.rtx2070.webgpuMs} ms` : '–',
        ];
      }),
    ),
  );
  out.push('');
  const stageLines = r.naive
    .filter((n) => Object.keys(n.stagesMeanMs).length)
    .map((n) => {
      const total = Object.values(n.stagesMeanMs).reduce((a, b) => a + b, 0);
      return `${n.label}: ${Object.entries(n.stagesMeanMs)
        .map(([k, x]) => `${k} ${ms(x)} ms (${((100 * x) / total).toFixed(0)}%)`)
        .join(', ')}`;
    });
  if (stageLines.length) {
    out.push(`Where the naive time goes (mean GPU ms per stage): ${stageLines.join('; ')}.`);
    out.push('');
  }
  out.push(
    `Paper rows without a volume of ours: ${NAIVE_MC.filter((p) => !r.naive.some((n) => n.paperName === p.dataset))
      .map(
        (p) =>
          `${p.dataset} (Surface Pro 7 ${p.surfacePro7.vulkanMs} / ${p.surfacePro7.webgpuMs ?? 'failed'} ms, RTX 2070 ${p.rtx2070.vulkanMs} / ${p.rtx2070.webgpuMs} ms)`,
      )
      .join('; ')}.`,
  );
  out.push('');

  // ------------------------------------------------------------ zfp
  const chromeGpu = r.zfp.some((z) => z.mbps.webgpuChromium !== undefined);
  out.push('## Full-volume ZFP decompression (paper Table 3)');
  out.push('');
  out.push(
    `Each volume's decoded field compressed by zfpy (zfp 1.0.1) at fixed rates ${r.settings.zfpRates.join(', ')} with header, then decoded whole ${r.settings.zfpRuns} times after a discarded first; ` +
      "MB/s = decompressed float32 bytes (10⁶) per second, from the mean time. Ours: GPU time of the decode pass, in Node (Dawn) and in Chromium's WebGPU (the paper's Vulkan and WebGPU columns are native vs browser likewise); zfp serial: zfp's serial C decoder (native, the zfpy wheel), " +
      '`zfp_decompress` into a preallocated array (`zfpy._decompress(..., out=)`), and `zfpy.decompress_numpy` as users call it (header, allocation, decode); ' +
      "zfp Wasm: zfp 1.0.1's C decoder compiled with Debian's emcc -O3 (`wasm/dist/zfp.wasm`), its `zfp_decompress` call into a preallocated heap array. All decoders gave bit-identical fields" +
      (r.zfp.some((z) => !z.bitIdentical) ? ' **except where marked**' : '') +
      '.',
  );
  out.push('');
  out.push(
    table(
      [
        'volume',
        'rate',
        'compressed',
        'ours, WebGPU (Dawn) MB/s',
        ...(chromeGpu ? ['ours, WebGPU (Chromium) MB/s'] : []),
        'zfp serial MB/s',
        'zfpy.decompress_numpy MB/s',
        'zfp Wasm, Node MB/s',
        'zfp Wasm, Chromium MB/s',
        'ours (Dawn) / serial',
        'Wasm (Node) / serial',
      ],
      r.zfp.map((z) => [
        r.volumes.find((v) => v.key === z.volume)?.label ?? z.volume,
        z.rate,
        mib(z.compressedBytes),
        f1(z.mbps.webgpu, 0),
        ...(chromeGpu ? [f1(z.mbps.webgpuChromium, 0)] : []),
        f1(z.mbps.zfpySerial, 0),
        f1(z.mbps.zfpyDecompressNumpy, 0),
        f1(z.mbps.wasmNode, 0),
        f1(z.mbps.wasmChromium, 0),
        ratio(z.mbps.webgpu / z.mbps.zfpySerial),
        ratio(z.mbps.wasmNode / z.mbps.zfpySerial) + (z.bitIdentical ? '' : ' (bits differ!)'),
      ]),
    ),
  );
  out.push('');
  out.push(
    'Paper (mean of 10 runs over rates 2, 4 and 8; ZFP 0.5.5-rc1; their data sets, not ours: the Skull is the same size as our bonsai):',
  );
  out.push('');
  out.push(
    table(
      ['data set', 'machine', 'figures as published'],
      ZFP.map((z) => [
        z.dataset,
        z.machine,
        Object.entries(z.columns)
          .map(([k, v]) => `${k} ${v}`)
          .join(', '),
      ]),
      ['l', 'l', 'l'],
    ),
  );
  out.push('');

  // ------------------------------------------------------------ block
  out.push('## Block-compressed isosurfaces: random, sweep up, sweep down (paper Table 5)');
  out.push('');
  out.push(
    "The isosurface pipeline (`src/isosurface/`) through the shared harness (`src/bench/harness.ts`, as `cli bench` and the page): per mode a cold LRU cache and the seeded sequence over the volume's range, " +
      `first surface discarded; hit rate = 1 - new/active blocks; GPU ms from timestamps (${r.gpuTiming}). The random mode uses the same isovalues as the tables above; its triangle counts equal the serial ones` +
      (r.block.some((b) => b.trianglesMatchSerial === false) ? ' **except where marked**' : '') +
      '.',
  );
  out.push('');
  const modeCell = (b: PaperBenchResult['block'][number], mode: string) => {
    const s = b.summaries.find((x) => x.mode === mode);
    return s ? `${pct(s.meanHitRate)}, ${ms(s.meanMs)} ms` : '–';
  };
  out.push(
    table(
      [
        'volume',
        'blocks',
        'surfaces per mode',
        'random: hit rate, mean ms',
        'sweep up',
        'sweep down',
        'naive ms (same random isovalues)',
        'naive / block random',
        'GPU memory (stream + cache + vertices, peak)',
        'naive GPU memory',
      ],
      r.block.map((b) => {
        const nb = h.naiveVsBlock.find((x) => x.volume === b.volume);
        const n = r.naive.find((x) => x.volume === b.volume);
        const kept = Math.max(...b.summaries.map((x) => x.count));
        return [
          r.volumes.find((v) => v.key === b.volume)?.label ?? b.volume,
          b.blockCount,
          kept,
          modeCell(b, 'random'),
          modeCell(b, 'sweep-up'),
          modeCell(b, 'sweep-down'),
          nb ? `${ms(nb.naiveMs)} (${nb.surfaces})` : '–',
          ratio(nb?.ratio),
          mib((b.memory.fixedBytes ?? 0) + b.memory.cacheBytesMax + b.memory.vertexBytesMax),
          n ? mib(n.memoryBytes) : '–',
        ];
      }),
    ),
  );
  out.push('');
  out.push('Paper (their data sets, 100 isovalues per benchmark; hit rate, RTX 2070 ms, Surface Pro 7 ms as published):');
  out.push('');
  const p3 = (x: [number, number, number | null]) => `${x[0]}%, ${x[1]} ms, ${x[2] === null ? 'oom' : `${x[2]} ms`}`;
  out.push(
    table(
      ['data set', 'random', 'sweep up', 'sweep down'],
      BLOCK.map((b) => [b.dataset, p3(b.random), p3(b.sweepUp), p3(b.sweepDown)]),
      ['l', 'l', 'l', 'l'],
    ),
  );
  out.push('');

  // ------------------------------------------------------------ choices
  out.push('## What was chosen, and why');
  out.push('');
  out.push(
    table(
      ['volume', 'file', 'how', 'isovalue range', 'chosen by', 'data-driven range'],
      r.volumes.map((v) => [
        v.label,
        v.file,
        v.how,
        `${f1(v.range[0], 2)} – ${f1(v.range[1], 2)}`,
        v.rangeSource,
        `${f1(v.dataRange[0], 2)} – ${f1(v.dataRange[1], 2)}`,
      ]),
      ['l', 'l', 'l', 'r', 'l', 'r'],
    ),
  );
  out.push('');
  for (const note of r.notes) out.push(`- ${note}`);
  out.push('');
  out.push(
    `Paper figures checked against paper.tex: ${r.paperCheck === null ? 'paper.tex not found' : r.paperCheck.length === 0 ? 'every quoted row found verbatim' : `**missing**: ${r.paperCheck.join('; ')}`}.`,
  );
  out.push('');
  return out.join('\n');
}

function span(xs: number[]): string {
  const lo = ratio(Math.min(...xs));
  const hi = ratio(Math.max(...xs));
  return lo === hi ? lo : `${lo}–${hi}`;
}

/** What the figures say, computed from them (so the words cannot drift from the numbers). */
function readingNotes(r: PaperBenchResult): string[] {
  const lines: string[] = ['**Reading these figures.**', ''];
  const h = r.headline;
  if (h.serial.wasmNodeVsNative !== undefined) {
    lines.push(
      `- Serial MC: our Wasm takes ${ratio(h.serial.wasmNodeVsNative)} the native time in Node${h.serial.wasmChromiumVsNative ? ` and ${ratio(h.serial.wasmChromiumVsNative)} in Chromium` : ''} ` +
        `(paper: ${SERIAL_MC.firefox.wasmVsNative}× in Firefox, ${SERIAL_MC.chrome.wasmVsNative}× in Chrome); JS ${ratio(h.serial.jsNodeVsNative)} in Node${h.serial.jsChromiumVsNative ? ` and ${ratio(h.serial.jsChromiumVsNative)} in Chromium` : ''} ` +
        `(paper: ${SERIAL_MC.firefox.jsVsNative}× in Firefox, ${SERIAL_MC.chrome.jsVsNative}× in Chrome). These are CPU figures on both sides, so they compare directly, the machines aside.`,
    );
  }
  const nb = h.naiveVsBlock;
  if (nb.length) {
    const faster = nb.filter((x) => x.ratio > 1);
    const slower = nb.filter((x) => x.ratio <= 1);
    const mem = nb
      .map((x) => {
        const b = r.block.find((y) => y.volume === x.volume);
        const n = r.naive.find((y) => y.volume === x.volume);
        return b && n
          ? `${x.label} ${mib((b.memory.fixedBytes ?? 0) + b.memory.cacheBytesMax + b.memory.vertexBytesMax)} vs ${mib(n.memoryBytes)}`
          : undefined;
      })
      .filter((x) => x !== undefined);
    lines.push(
      `- Naive vs block-compressed, same device and isovalues: the block pipeline is ${faster.map((x) => `${ratio(x.ratio)} faster on ${x.label}`).join(', ') || 'not faster anywhere'}` +
        (slower.length
          ? `, and slower on ${slower.map((x) => `${x.label} (naive / block ${ratio(x.ratio)})`).join(', ')}, where its fixed per-surface cost (tens of passes: active blocks, the cache update with its radix sort, block MC) weighs more than touching every cell of a small volume`
          : '') +
        `. The naive MC needs the whole decompressed volume plus 12 bytes per cell on the GPU; the block pipeline the compressed stream, the cache and the vertices (peak GPU memory, block vs naive: ${mem.join('; ')}).`,
    );
  }
  if (h.zfp.length) {
    const g = h.zfp.map((x) => x.webgpuVsSerial);
    const w = h.zfp.map((x) => x.wasmNodeVsSerial);
    lines.push(
      `- zfp decompression: our WebGPU decoder reaches ${span(g)} of zfp's serial decoder's throughput here` +
        (r.adapter.software
          ? ', because SwiftShader runs the "GPU" kernel on 2 CPU cores through an emulator; the paper\'s WebGPU decoder was 2.1-2.2× its serial CPU decoder on the Surface Pro 7\'s integrated GPU and 7.6-13.7 GB/s on the RTX 2070. Run `npm run bench:paper` on a machine with a GPU, or open `/paper-bench.html` in a browser on one, for GPU figures.'
          : '.') +
        ` zfp's own C decoder in Wasm runs at ${span(w)} of its native throughput.`,
    );
  }
  const rows = r.block.map((b) => {
    const v = r.volumes.find((x) => x.key === b.volume)?.label ?? b.volume;
    const hr = (m: string) => pct(b.summaries.find((x) => x.mode === m)?.meanHitRate);
    return `${v} ${hr('random')} / ${hr('sweep-up')} / ${hr('sweep-down')}`;
  });
  const hitOf = (b: PaperBenchResult['block'][number], m: string) => b.summaries.find((x) => x.mode === m)?.meanHitRate ?? NaN;
  const nested = r.block.every((b) => hitOf(b, 'sweep-up') >= hitOf(b, 'random') && hitOf(b, 'random') >= hitOf(b, 'sweep-down'));
  if (rows.length) {
    lines.push(
      `- Cache hit rates (random / sweep up / sweep down) depend on the data and the cache, not on the hardware, so they compare with the paper's directly: ${rows.join('; ')}; the paper's 256³ CT scans: Skull 98.4% / 100% / 94.8%, Foot 98.9% / 100% / 97.4%. ` +
        (nested ? "As on the paper's nested-surface data sets, sweep up hits most and sweep down least on every volume." : ''),
    );
  }
  lines.push('');
  return lines;
}
