// `npm run bench:paper [-- --quick] [--volume FILE[:lo,hi]] ...`: the paper's
// comparison benchmarks, headless, in one command (Usher & Pascucci, LDAV
// 2020, Tables 2, 3 and 5 and Figure 6):
//
//   1. serial marching cubes: native C++ (g++ -O3), the same C++ in Wasm and
//      the TypeScript version, in Node and in headless Chromium;
//   2. the naive data-parallel marching cubes in WebGPU over the whole volume;
//   3. full-volume zfp decompression at rates 2, 4, 8: our WebGPU decoder,
//      zfp's serial C decoder (zfpy) and zfp's C decoder in Wasm (Node, Chromium);
//   4. the block-compressed isosurface pipeline: random, sweep up, sweep down.
//
// Writes benchmarks/results/<date>-<adapter>[-quick].json and .md (the
// report: one table per paper table, our figures beside the published ones).
// The full run fits 30 minutes and --quick 5 on a 2-core machine without a
// GPU (WebGPU on SwiftShader); see benchmarks/paper/README.md.
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { cpus, loadavg, tmpdir, totalmem } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { isovalueSequence, type BenchMode } from '../../src/bench/sequences.ts';
import { describeAdapter } from '../../src/gpu/device.ts';
import { requestNodeGpu } from '../../src/gpu/node-gpu.ts';
import { NaiveMarchingCubes, type NaiveMcResult } from '../../src/mc/naive-gpu.ts';
import { meanAfterFirst } from '../../src/examples/paper-bench/measure.ts';
import { ZfpDecoder } from '../../src/zfp/decoder.ts';
import { runBlock, type BlockResult } from './block.ts';
import { BrowserBench } from './browser.ts';
import { checkAgainstPaper } from './paper-figures.ts';
import { writeReport } from './report.ts';
import type { NaiveEntry, PaperBenchResult, SerialEntry } from './result.ts';
import { nativeBinary, runSerialNode } from './serial.ts';
import { prepareVolume, sharedVolumes, userVolume, type PreparedVolume, type VolumeSpec } from './volumes.ts';
import { mbPerSecond, runZfpVolume, type ZfpRateResult } from './zfp.ts';

const ROOT = fileURLToPath(new URL('../../', import.meta.url));
const SHARED_DATA = join(ROOT, '..', 'shared', 'data');
const PAPER_TEX = join(ROOT, '..', 'shared', 'reference', 'paper.tex');
const MODES: BenchMode[] = ['random', 'sweep-up', 'sweep-down'];

// ---------------------------------------------------------------- plans

interface Plan {
  limitSeconds: number;
  sharedVolumes: string[];
  /** Isovalues for serial MC (Node and Chromium). */
  serial: number;
  /** Surfaces of the naive GPU MC, by volume size. */
  naiveCount: (voxels: number) => number;
  /** Surfaces per mode of the block-compressed benchmark, by volume size. */
  blockCount: (voxels: number) => number;
  zfpRuns: number;
  zfpRates: number[];
  /** Safety caps (seconds): a loop past its cap stops early and the report says so. */
  naiveCapSeconds: number;
  blockCapSecondsPerMode: number;
  browserCallTimeoutSeconds: number;
}

/**
 * Full: 100 isovalues everywhere the paper has 100, except where SwiftShader
 * is slowest: the naive MC touches every cell (about 2-5 s per bonsai surface
 * there), so 50 surfaces on a 256^3 volume; the block pipeline (1-2 s per
 * bonsai surface) keeps 100 per mode up to 256^3. Both scale down with the
 * volume beyond. Measured on the 2-core development machine under load: about
 * 15 minutes in all. Quick: fuel and hydrogen, 20 isovalues for serial MC and
 * 10 for the GPU methods, 3 decode runs: about a minute.
 */
const PLANS: Record<'full' | 'quick', Plan> = {
  full: {
    limitSeconds: 30 * 60,
    sharedVolumes: ['fuel', 'hydrogen', 'bonsai'],
    serial: 100,
    naiveCount: (voxels) => (voxels <= 128 ** 3 ? 100 : Math.max(10, Math.round((50 * 256 ** 3) / voxels))),
    blockCount: (voxels) => Math.max(10, Math.min(100, Math.round((100 * 256 ** 3) / voxels))),
    zfpRuns: 10,
    zfpRates: [2, 4, 8],
    naiveCapSeconds: 300,
    blockCapSecondsPerMode: 240,
    browserCallTimeoutSeconds: 600,
  },
  quick: {
    limitSeconds: 5 * 60,
    sharedVolumes: ['fuel', 'hydrogen'],
    serial: 20,
    naiveCount: () => 10,
    blockCount: () => 10,
    zfpRuns: 3,
    zfpRates: [2, 4, 8],
    naiveCapSeconds: 25,
    blockCapSecondsPerMode: 15,
    browserCallTimeoutSeconds: 180,
  },
};

// ---------------------------------------------------------------- arguments

const USAGE = `usage: npm run bench:paper -- [--quick] [--volume FILE[:lo,hi]]... [--volumes fuel,hydrogen,bonsai|none]
       [--count N] [--seed S] [--rate R] [--no-browser] [--no-browser-webgpu] [--out DIR]
  --quick            fuel and hydrogen, 20 isovalues for serial MC, 10 for the GPU methods, 3 decode runs (1-2 minutes)
  --volume FILE      also a volume of yours: zfp (fixed rate) or name_XxYxZ_dtype.raw (compressed on the GPU at --rate, default 8);
                     :lo,hi gives its isovalue range (default: from the data)
  --volumes LIST     which shared volumes (default: all three; quick: fuel,hydrogen)
  --count N          isovalues per method and mode everywhere (overrides the plan)
  --no-browser       skip the Chromium columns
  --no-browser-webgpu  skip the WebGPU runs in Chromium (naive MC, our zfp decoder), keeping its serial MC and zfp Wasm
  --out DIR          where the JSON and Markdown go (default benchmarks/results)
  --report FILE.json only rewrite the Markdown report of an earlier run from its JSON`;

interface Args {
  quick: boolean;
  volumes: string[];
  shared?: string[];
  count?: number;
  seed: number;
  rate?: number;
  browser: boolean;
  browserWebGpu: boolean;
  out: string;
}

function parseArgs(argv: string[]): Args {
  const a: Args = { quick: false, volumes: [], seed: 1, browser: true, browserWebGpu: true, out: join(ROOT, 'benchmarks', 'results') };
  for (let i = 0; i < argv.length; i++) {
    const k = argv[i];
    const next = () => {
      const v = argv[++i];
      if (v === undefined) throw new UsageError(`${k} needs a value`);
      return v;
    };
    const int = (v: string) => {
      const n = Number(v);
      if (!Number.isInteger(n)) throw new UsageError(`${k} takes an integer (got ${v})`);
      return n;
    };
    if (k === '--quick') a.quick = true;
    else if (k === '--volume') a.volumes.push(next());
    else if (k === '--volumes') a.shared = next() === 'none' ? [] : argv[i].split(',');
    else if (k === '--count') a.count = int(next());
    else if (k === '--seed') a.seed = int(next());
    else if (k === '--rate') a.rate = Number(next());
    else if (k === '--no-browser') a.browser = false;
    else if (k === '--no-browser-webgpu') a.browserWebGpu = false;
    else if (k === '--out') a.out = next();
    else if (k === '--help' || k === '-h') {
      console.log(USAGE);
      process.exit(0);
    } else throw new UsageError(`unknown option ${k}`);
  }
  if (a.count !== undefined && a.count < 2) throw new UsageError('--count must be at least 2 (the first surface is discarded)');
  if (a.rate !== undefined && !(a.rate > 0)) throw new UsageError('--rate must be positive');
  for (const s of a.shared ?? [])
    if (!['fuel', 'hydrogen', 'bonsai'].includes(s)) throw new UsageError(`--volumes: unknown shared volume ${s} (fuel, hydrogen, bonsai)`);
  return a;
}

class UsageError extends Error {}

// ---------------------------------------------------------------- helpers

const t0 = performance.now();
const elapsed = () => (performance.now() - t0) / 1000;
function log(s: string): void {
  console.error(`[bench:paper ${elapsed().toFixed(0).padStart(4)} s] ${s}`);
}

function cpuModel(): string {
  try {
    const m = /^model name\s*:\s*(.+)$/m.exec(readFileSync('/proc/cpuinfo', 'utf8'));
    if (m) return m[1].trim();
  } catch {
    /* not Linux */
  }
  return cpus()[0]?.model ?? 'unknown CPU';
}

function dawnVersion(): string {
  try {
    return JSON.parse(readFileSync(join(ROOT, 'node_modules', 'webgpu', 'package.json'), 'utf8')).version;
  } catch {
    return '?';
  }
}

const mean = (xs: number[]) => xs.reduce((s, x) => s + x, 0) / Math.max(1, xs.length);
const defined = <T>(x: T | undefined): x is T => x !== undefined && !(typeof x === 'number' && !Number.isFinite(x));

function localDate(d: Date): string {
  const p = (n: number) => String(n).padStart(2, '0');
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())}`;
}

// ---------------------------------------------------------------- main

async function main(): Promise<void> {
  const reportAt = process.argv.indexOf('--report');
  if (reportAt >= 0) {
    // Rewrites the Markdown of an earlier run from its JSON (e.g. after improving the report).
    const file = process.argv[reportAt + 1];
    if (!file?.endsWith('.json') || !existsSync(file)) throw new UsageError('--report takes the JSON of an earlier run');
    const md = file.replace(/\.json$/, '.md');
    writeFileSync(md, writeReport(JSON.parse(readFileSync(file, 'utf8')) as PaperBenchResult));
    console.log(`wrote ${md}`);
    return;
  }
  const args = parseArgs(process.argv.slice(2));
  const mode = args.quick ? 'quick' : 'full';
  const plan = PLANS[mode];
  const command = ['npm run bench:paper', ...(process.argv.length > 2 ? ['--', ...process.argv.slice(2)] : [])].join(' ');
  const loadStart = loadavg();
  const sections: Record<string, number> = {};
  const errors: PaperBenchResult['errors'] = [];
  const notes: string[] = [];
  const section = async <T>(name: string, fn: () => Promise<T>): Promise<T> => {
    const s = performance.now();
    try {
      return await fn();
    } finally {
      sections[name] = (sections[name] ?? 0) + (performance.now() - s) / 1000;
    }
  };
  const attempt = async (name: string, volume: string | undefined, fn: () => Promise<void>) => {
    try {
      await fn();
    } catch (e) {
      const message = (e as Error).message ?? String(e);
      errors.push({ section: name, volume, message });
      log(`ERROR in ${name}${volume ? ` (${volume})` : ''}: ${message}`);
    }
  };

  if (!existsSync(join(ROOT, '.venv', 'bin', 'python'))) {
    throw new Error(
      `${join(ROOT, '.venv', 'bin', 'python')} is missing: run \`npm test\` once (it installs tests/python-requirements.txt into .venv, with zfpy)`,
    );
  }
  const specs: VolumeSpec[] = [];
  if (existsSync(SHARED_DATA)) {
    const wanted = args.shared ?? plan.sharedVolumes;
    specs.push(...sharedVolumes(SHARED_DATA).filter((v) => wanted.includes(v.key)));
  } else if (!args.volumes.length) {
    throw new Error(`the shared volumes are not at ${SHARED_DATA}; give volumes with --volume FILE`);
  }
  for (const v of args.volumes) {
    const spec = userVolume(v);
    if (!existsSync(spec.path)) throw new UsageError(`--volume ${spec.path}: no such file`);
    specs.push(spec);
  }
  if (specs.length === 0) throw new UsageError('no volumes: give --volume FILE or leave --volumes out');

  log(`${mode} run: ${specs.map((s) => s.key).join(', ')}; limit ${plan.limitSeconds / 60} min`);
  const gpu = await requestNodeGpu({ label: 'benchPaper.device', onFailure: (f) => log(`WebGPU ${f.kind}: ${f.message}`) });
  const adapterDescription = describeAdapter(gpu.adapter);
  const adapterSlug = (gpu.adapter.architecture || gpu.adapter.vendor || 'unknown')
    .toLowerCase()
    .replace(/[^a-z0-9]+/g, '-')
    .replace(/^-|-$/g, '');
  log(`adapter: ${adapterDescription}`);
  const decoder = await ZfpDecoder.create(gpu.device);
  const dir = mkdtempSync(join(tmpdir(), 'bench-paper-'));
  const volumes: PreparedVolume[] = [];
  const result: Partial<PaperBenchResult> = {};
  let browser: BrowserBench | undefined;
  const chromium: PaperBenchResult['chromium'] = { flags: [] };
  const serial: SerialEntry[] = [];
  const naive: NaiveEntry[] = [];
  const zfp: ZfpRateResult[] = [];
  const block: PaperBenchResult['block'] = [];
  const naiveCounts: Record<string, number> = {};
  const blockCounts: Record<string, number> = {};
  const native = nativeBinary(ROOT);
  const serialCount = args.count ?? plan.serial;
  if (native.error) log(`native serial MC unavailable: ${native.error}`);

  try {
    // -------------------------------------------------------------- volumes
    await section('volumes', async () => {
      for (const spec of specs) {
        await attempt('volumes', spec.key, async () => {
          const v = await prepareVolume(gpu, decoder, spec, dir, args.rate);
          volumes.push(v);
          naiveCounts[v.key] = args.count ?? plan.naiveCount(v.dims[0] * v.dims[1] * v.dims[2]);
          blockCounts[v.key] = args.count ?? plan.blockCount(v.dims[0] * v.dims[1] * v.dims[2]);
          log(`${v.label}: ${v.dims.join('x')}, ${v.how}; range ${v.range.map((x) => x.toFixed(2)).join('..')} (${v.rangeSource})`);
        });
      }
    });
    const isovaluesOf = (v: PreparedVolume, n: number) => isovalueSequence('random', n, v.range, args.seed);

    // -------------------------------------------------------------- serial, Node
    await section('serial MC (Node)', async () => {
      for (const v of volumes) {
        await attempt('serial MC (Node)', v.key, async () => {
          const isovalues = isovaluesOf(v, serialCount);
          log(`serial MC in Node: ${v.label}, ${isovalues.length} isovalues (native, Wasm, JS)...`);
          const r = await runSerialNode(v, isovalues, native.path, native.error);
          serial.push({
            volume: v.key,
            label: v.label,
            isovalues,
            native: r.native,
            wasmNode: r.wasm,
            jsNode: r.js,
            means: {
              native: r.native ? meanAfterFirst(r.native.ms) : undefined,
              wasmNode: meanAfterFirst(r.wasm.ms),
              jsNode: meanAfterFirst(r.js.ms),
            },
          });
        });
      }
    });

    // -------------------------------------------------------------- zfp decompression (Node side writes the streams)
    await section('zfp decompression', async () => {
      for (const v of volumes) {
        await attempt('zfp decompression', v.key, async () => {
          log(`zfp decompression: ${v.label}, rates ${plan.zfpRates.join(', ')}, ${plan.zfpRuns} runs (+1)...`);
          zfp.push(...(await runZfpVolume(ROOT, gpu, decoder, v, dir, plan.zfpRates, plan.zfpRuns)));
        });
      }
    });

    // -------------------------------------------------------------- Chromium
    if (args.browser) {
      await section('Chromium', async () => {
        await attempt('Chromium', undefined, async () => {
          browser = await BrowserBench.start(ROOT, dir, gpu.adapter.software, log);
          Object.assign(chromium, {
            version: browser.info.chromium,
            userAgent: browser.info.userAgent,
            flags: browser.info.flags,
            hardwareConcurrency: browser.info.hardwareConcurrency,
          });
          log(`Chromium ${browser.info.chromium} ready`);
        });
        if (!browser) {
          chromium.error = errors.find((e) => e.section === 'Chromium')?.message;
          return;
        }
        const timeout = plan.browserCallTimeoutSeconds * 1000;
        for (const s of serial) {
          const v = volumes.find((x) => x.key === s.volume)!;
          await attempt('serial MC (Chromium)', v.key, async () => {
            log(`serial MC in Chromium: ${v.label}, ${s.isovalues.length} isovalues (Wasm, JS)...`);
            const t = await browser!.serialMc(
              { url: browser!.dataUrl(v.rawPath.split('/').pop()!), dims: v.dims, isovalues: s.isovalues, methods: ['js', 'wasm'] },
              timeout,
            );
            const bad = t.js!.triangles.findIndex((n, i) => n !== s.jsNode.triangles[i]);
            if (bad >= 0)
              throw new Error(
                `Chromium gave ${t.js!.triangles[bad]} triangles at iso ${s.isovalues[bad]}, Node ${s.jsNode.triangles[bad]}`,
              );
            s.jsChromium = t.js;
            s.wasmChromium = t.wasm;
            s.means.jsChromium = meanAfterFirst(t.js!.ms);
            s.means.wasmChromium = meanAfterFirst(t.wasm!.ms);
          });
        }
        for (const z of zfp) {
          await attempt('zfp Wasm (Chromium)', z.volume, async () => {
            log(`zfp Wasm decode in Chromium: ${z.file}...`);
            const t = await browser!.zfpWasm({ url: browser!.dataUrl(z.file), runs: plan.zfpRuns + 1 }, timeout);
            z.wasmChromiumMs = t.ms;
            z.mbps.wasmChromium = mbPerSecond(z.floatBytes, t.ms);
          });
        }
      });
    } else {
      chromium.error = 'skipped (--no-browser)';
    }

    // -------------------------------------------------------------- naive GPU MC and block-compressed, interleaved
    // The block benchmark runs through the shared harness; during its random
    // mode, right after each of the first `naiveCount` surfaces, the naive MC
    // computes the same isovalue, so the two see the same machine load (a busy
    // 2-core machine drifts by 2x over minutes) and the naive/block ratio is
    // taken under equal conditions. The naive times of Table 2 are these.
    await section('naive GPU MC + block-compressed', async () => {
      for (const v of volumes) {
        await attempt('naive GPU MC + block-compressed', v.key, async () => {
          const naiveCount = naiveCounts[v.key];
          const blockCount = blockCounts[v.key];
          const isovalues = isovaluesOf(v, naiveCount);
          const s = serial.find((x) => x.volume === v.key);
          const volumeBuffer = decoder.decodeVolume(v.stream);
          const mc = await NaiveMarchingCubes.create(gpu.device, {
            dims: v.dims,
            initialVertexCapacity: s ? 3 * Math.max(...s.jsNode.triangles) : undefined,
          });
          const res: NaiveMcResult[] = [];
          let naiveStart = 0;
          let naiveSpent = 0;
          let b: BlockResult;
          try {
            log(
              `naive GPU MC (${naiveCount} isovalues, paired with the random mode) and block-compressed (${blockCount} isovalues per mode): ${v.label}...`,
            );
            b = await runBlock(gpu, v, MODES, blockCount, args.seed, {
              capSecondsPerMode: plan.blockCapSecondsPerMode,
              onProgress: (m, d, n) => {
                if (d % 25 === 0) log(`  ${v.key} ${m} ${d}/${n}${m === 'random' ? ` (naive ${res.length})` : ''}`);
              },
              pairRandom: async (iso, index) => {
                if (index >= naiveCount || naiveSpent > plan.naiveCapSeconds * 1000) return undefined;
                if (iso !== isovalues[index])
                  throw new Error(`the random mode's isovalue ${index} is ${iso}, the naive MC's ${isovalues[index]}`);
                naiveStart = performance.now();
                res.push(await mc.extract(volumeBuffer, iso));
                const ms = performance.now() - naiveStart;
                naiveSpent += ms;
                return ms;
              },
            });
          } finally {
            mc.destroy();
            volumeBuffer.destroy();
          }
          const done = res.length;
          const stages: Record<string, number> = {};
          for (const r of res.slice(1))
            for (const st of r.stages) stages[st.label] = (stages[st.label] ?? 0) + st.ms / Math.max(1, done - 1);
          const matches = s ? res.every((r, i) => i >= s.jsNode.triangles.length || r.triangles === s.jsNode.triangles[i]) : true;
          if (!matches) errors.push({ section: 'naive GPU MC', volume: v.key, message: 'triangle counts differ from the serial MC' });
          if (done < naiveCount)
            notes.push(
              `Naive GPU MC on ${v.label} stopped after ${done} of ${naiveCount} surfaces (${plan.naiveCapSeconds} s cap, or the random mode's).`,
            );
          naive.push({
            volume: v.key,
            label: v.label,
            paperName: v.paperName,
            isovalues: isovalues.slice(0, done),
            ms: res.map((r) => r.gpuMs),
            wallMs: res.map((r) => r.wallMs),
            triangles: res.map((r) => r.triangles),
            activeCells: res.map((r) => r.activeCells),
            stagesMeanMs: stages,
            trianglesMatchSerial: matches,
            memoryBytes: v.dims[0] * v.dims[1] * v.dims[2] * 4 + mc.memoryBytes,
            serialNativeMs: s?.native && done > 1 ? meanAfterFirst(s.native.ms.slice(0, done)) : undefined,
            cappedAt: done < naiveCount ? done : undefined,
          });
          const random = b.records.filter((r) => r.mode === 'random');
          const trianglesMatchSerial = s
            ? random.every((r) => r.index >= s.jsNode.triangles.length || r.triangles === s.jsNode.triangles[r.index])
            : undefined;
          if (trianglesMatchSerial === false)
            errors.push({ section: 'block-compressed', volume: v.key, message: 'random-mode triangle counts differ from the serial MC' });
          const cappedModes = MODES.filter((m) => b.records.filter((r) => r.mode === m).length < blockCount);
          for (const m of cappedModes)
            notes.push(
              `Block-compressed ${m} on ${v.label} stopped after ${b.records.filter((r) => r.mode === m).length} of ${blockCount} surfaces (${plan.blockCapSecondsPerMode} s cap per mode).`,
            );
          block.push({ ...b, trianglesMatchSerial, cappedModes });
        });
      }
    });

    // -------------------------------------------------------------- WebGPU in Chromium
    if (browser && args.browserWebGpu) {
      const b = browser;
      const timeout = plan.browserCallTimeoutSeconds * 1000;
      await section('WebGPU in Chromium', async () => {
        for (const entry of naive) {
          const v = volumes.find((x) => x.key === entry.volume)!;
          if (!v.zfpPath) {
            notes.push(`No Chromium WebGPU runs for ${v.label}: the page opens zfp files with a header, and this one has none.`);
            continue;
          }
          await attempt('naive GPU MC (Chromium)', v.key, async () => {
            log(`naive MC in Chromium's WebGPU: ${v.label}, ${entry.isovalues.length} isovalues...`);
            const s = serial.find((x) => x.volume === v.key);
            const c = await b.naiveMc(
              {
                url: b.dataUrl(v.zfpPath!.split('/').pop()!),
                isovalues: entry.isovalues,
                vertexCapacity: s ? 3 * Math.max(...s.jsNode.triangles) : undefined,
              },
              timeout,
            );
            const bad = c.triangles.findIndex((n, i) => n !== entry.triangles[i]);
            if (bad >= 0)
              throw new Error(
                `naive MC in Chromium gave ${c.triangles[bad]} triangles at iso ${entry.isovalues[bad]}, in Node ${entry.triangles[bad]}`,
              );
            entry.chromiumMs = c.ms;
          });
        }
        for (const z of zfp) {
          await attempt('zfp WebGPU (Chromium)', z.volume, async () => {
            log(`our WebGPU zfp decoder in Chromium: ${z.file}...`);
            const t = await b.gpuDecode({ url: b.dataUrl(z.file), runs: plan.zfpRuns + 1 }, timeout);
            z.webgpuChromiumMs = t.ms;
            z.mbps.webgpuChromium = mbPerSecond(z.floatBytes, t.ms);
          });
        }
      });
    }
  } finally {
    if (browser) await browser.close();
    for (const v of volumes) v.stream.destroy();
    decoder.destroy();
    rmSync(dir, { recursive: true, force: true });
  }

  // -------------------------------------------------------------- headline
  const serialRatio = (num: (s: SerialEntry) => number | undefined, den: (s: SerialEntry) => number | undefined) => {
    const rs = serial.map((s) => (defined(num(s)) && defined(den(s)) ? num(s)! / den(s)! : undefined)).filter(defined);
    return rs.length ? mean(rs) : undefined;
  };
  const naiveVsBlock: PaperBenchResult['headline']['naiveVsBlock'] = [];
  for (const n of naive) {
    const b = block.find((x) => x.volume === n.volume);
    if (!b || n.ms.length < 2) continue;
    const random = b.records.filter((r) => r.mode === 'random' && !r.discarded);
    const same = random.filter((r) => r.index < n.ms.length);
    if (!same.length) continue;
    const blockMs = mean(same.map((r) => r.gpuMs));
    const naiveMs = mean(n.ms.slice(1, 1 + same.length));
    naiveVsBlock.push({
      volume: n.volume,
      label: n.label,
      surfaces: same.length,
      naiveMs,
      blockMs,
      ratio: naiveMs / blockMs,
      blockRandomAllMs: mean(random.map((r) => r.gpuMs)),
    });
  }
  const rates = [...new Set(zfp.map((z) => z.rate))];
  const zfpHeadline = rates.map((rate) => {
    const zs = zfp.filter((z) => z.rate === rate);
    const chromium = zs.filter((z) => defined(z.mbps.wasmChromium));
    return {
      rate,
      webgpuVsSerial: mean(zs.map((z) => z.mbps.webgpu / z.mbps.zfpySerial)),
      wasmNodeVsSerial: mean(zs.map((z) => z.mbps.wasmNode / z.mbps.zfpySerial)),
      wasmChromiumVsSerial: chromium.length ? mean(chromium.map((z) => z.mbps.wasmChromium! / z.mbps.zfpySerial)) : undefined,
    };
  });

  notes.push(
    "Isovalues: `isovalueSequence` of src/bench/sequences.ts (seeded mulberry32, float32), the same generator as the block benchmark's random mode, so every method computes the same surfaces; a method run on fewer isovalues takes a prefix of the same sequence.",
    "Means: every method's first surface (or decode) is discarded as a warm-up, as in the paper; the JSON keeps every sample, and medians can be computed from it.",
    `Counts: serial MC ${serialCount} isovalues per volume; naive GPU MC ${Object.entries(naiveCounts)
      .map(([k, c]) => `${k} ${c}`)
      .join(', ')}; each block-compressed mode ${Object.entries(blockCounts)
      .map(([k, c]) => `${k} ${c}`)
      .join(
        ', ',
      )} (${mode === 'full' ? "the paper's 100, except the naive MC on volumes above 128³: on SwiftShader it needs seconds per surface (all 16.6 M cells of the bonsai), so 50 on a 256³ volume, and both GPU methods scale down with the volume beyond 256³, to fit the 30-minute budget" : 'quick run'}); zfp ${plan.zfpRuns} decodes per rate after a discarded first. Time caps per loop (naive ${plan.naiveCapSeconds} s per volume, block ${plan.blockCapSecondsPerMode} s per mode) stop a loop early on a slow or busy machine, and are reported.`,
    "Fuel is a float32 raw file: compressed on the GPU at rate 8 for the GPU pipelines, which is lossless for this data (its values are zfp's precision-8 decode), so all methods contour the raw values. Hydrogen (rate 8) and bonsai (rate 4) are used as compressed; serial and naive MC contour their zfp decode.",
    "Serial MC in Chromium runs in the page's main thread (paper-bench.html, built by Vite into a temporary folder and served locally); Wasm and JS take turns per isovalue, as in Node.",
    'zfp in the paper was 0.5.5-rc1 (serial CPU decoder, and their WebGPU/Vulkan ports of its CUDA decoder); here zfp 1.0.1 (zfpy for the native serial decoder, the same C in Wasm) and our own WebGPU decoder, bit-identical to zfp.',
  );

  const loadEnd = loadavg();
  const total = elapsed();
  const full: PaperBenchResult = {
    benchmark: 'paper',
    version: 1,
    date: new Date().toISOString(),
    mode,
    command,
    limits: { seconds: plan.limitSeconds },
    durations: { totalSeconds: total, sections },
    machine: {
      cpu: cpuModel(),
      cores: cpus().length,
      memoryGiB: Math.round(totalmem() / 2 ** 30),
      node: process.version,
      dawn: dawnVersion(),
      platform: `${process.platform} ${process.arch}`,
      loadAverage: { start: loadStart, end: loadEnd },
    },
    adapter: gpu.adapter,
    adapterDescription,
    adapterSlug,
    gpuTiming: gpu.device.features.has('timestamp-query') ? 'timestamp queries' : 'queue wall time (no timestamp-query)',
    chromium,
    serialNative: native.error ? { error: native.error } : { compiler: native.compiler },
    settings: {
      seed: args.seed,
      serialCounts: serialCount,
      naiveCounts,
      blockCounts,
      zfpRuns: plan.zfpRuns,
      zfpRates: plan.zfpRates,
      plan: {
        limitSeconds: plan.limitSeconds,
        naiveCapSeconds: plan.naiveCapSeconds,
        blockCapSecondsPerMode: plan.blockCapSecondsPerMode,
        browserCallTimeoutSeconds: plan.browserCallTimeoutSeconds,
      },
    },
    volumes: volumes.map((v) => ({
      key: v.key,
      label: v.label,
      file: v.path.replace(join(ROOT, '..') + '/', '../'),
      how: v.how,
      dims: v.dims,
      rate: v.rate,
      range: v.range,
      rangeSource: v.rangeSource,
      dataRange: v.dataRange,
    })),
    serial,
    naive,
    zfp,
    block,
    headline: {
      serial: {
        wasmNodeVsNative: serialRatio(
          (s) => s.means.wasmNode,
          (s) => s.means.native,
        ),
        jsNodeVsNative: serialRatio(
          (s) => s.means.jsNode,
          (s) => s.means.native,
        ),
        wasmChromiumVsNative: serialRatio(
          (s) => s.means.wasmChromium,
          (s) => s.means.native,
        ),
        jsChromiumVsNative: serialRatio(
          (s) => s.means.jsChromium,
          (s) => s.means.native,
        ),
        jsNodeVsWasmNode: serialRatio(
          (s) => s.means.jsNode,
          (s) => s.means.wasmNode,
        ),
        jsChromiumVsWasmChromium: serialRatio(
          (s) => s.means.jsChromium,
          (s) => s.means.wasmChromium,
        ),
      },
      naiveVsBlock,
      zfp: zfpHeadline,
    },
    notes,
    paperCheck: checkAgainstPaper(PAPER_TEX),
    errors,
  };
  Object.assign(result, full);
  const base = join(args.out, `${localDate(new Date())}-${adapterSlug}${mode === 'quick' ? '-quick' : ''}`);
  // Arrays of numbers on one line: the samples stay readable and the file small.
  const json = JSON.stringify(full, null, 2).replace(
    /\[\s+(-?[\d.eE+-]+(?:,\s+-?[\d.eE+-]+)*)\s+\]/g,
    (_, inner: string) => `[${inner.split(/,\s+/).join(', ')}]`,
  );
  mkdirSync(args.out, { recursive: true });
  writeFileSync(`${base}.json`, json + '\n');
  console.log(`wrote ${base}.json`);
  writeFileSync(`${base}.md`, writeReport(full));
  console.log(`wrote ${base}.md`);
  console.log(
    `\n${mode} run: ${(total / 60).toFixed(1)} min (limit ${plan.limitSeconds / 60} min)${errors.length ? `; ${errors.length} error(s), see the report` : ''}`,
  );
  gpu.device.destroy();
  if (errors.length) process.exitCode = 1;
}

main().catch((e) => {
  if (e instanceof UsageError) {
    console.error(`bench:paper: ${e.message}\n${USAGE}`);
    process.exit(2);
  }
  console.error(e);
  process.exit(1);
});
