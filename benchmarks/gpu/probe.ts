// bench:gpu's probe: what the adapter is and can do (info, limits, features,
// timestamp queries, subgroups and their sizes), what the machine says of its
// GPU (nvidia-smi where there is one), the copy bandwidth the other figures
// are read against, and whether a Chromium that could run the page benchmark
// is here.
import { spawnSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { repeat } from '../lib/report.ts';
import { BracketTimer } from '../primitives-timing.ts';
import type { BenchRun } from './context.ts';

const SECTION = 'probe';

export interface ProbeData {
  adapter: Record<string, unknown>;
  features: string[];
  limits: Record<string, number>;
  timestampQuery: boolean;
  subgroups: boolean;
  subgroupSizes?: [number, number];
  nvidiaSmi?: string;
  copyGBps: number;
}

function limitsOf(limits: GPUSupportedLimits): Record<string, number> {
  const out: Record<string, number> = {};
  // WebIDL attributes live on the prototype: walk it
  for (let o: object | null = limits; o && o !== Object.prototype; o = Object.getPrototypeOf(o)) {
    for (const k of Object.getOwnPropertyNames(o)) {
      const v = (limits as unknown as Record<string, unknown>)[k];
      if (typeof v === 'number' && !(k in out)) out[k] = v;
    }
  }
  return out;
}

function nvidiaSmi(): string | undefined {
  const r = spawnSync(
    'nvidia-smi',
    ['--query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem', '--format=csv,noheader'],
    {
      encoding: 'utf8',
      timeout: 20_000,
    },
  );
  return r.status === 0 ? r.stdout.trim() : undefined;
}

export async function probeSection(run: BenchRun): Promise<ProbeData> {
  const { gpu } = run;
  const info = (gpu.device as unknown as { adapterInfo?: GPUAdapterInfo }).adapterInfo;
  const infoRecord: Record<string, unknown> = { ...gpu.adapter };
  const sizes = info as unknown as { subgroupMinSize?: number; subgroupMaxSize?: number } | undefined;
  if (sizes?.subgroupMinSize) infoRecord.subgroupMinSize = sizes.subgroupMinSize;
  if (sizes?.subgroupMaxSize) infoRecord.subgroupMaxSize = sizes.subgroupMaxSize;
  const features = [...gpu.device.features].map(String).sort();
  const limits = limitsOf(gpu.device.limits);
  const smi = nvidiaSmi();
  console.log(`  adapter: ${JSON.stringify(infoRecord)}`);
  console.log(`  features: ${features.join(', ')}`);
  console.log(
    `  maxStorageBufferBindingSize ${limits.maxStorageBufferBindingSize}, maxBufferSize ${limits.maxBufferSize}, maxComputeWorkgroupStorageSize ${limits.maxComputeWorkgroupStorageSize}`,
  );
  if (smi) console.log(`  nvidia-smi: ${smi}`);

  // copy bandwidth: copyBufferToBuffer of 256 MiB (4 MiB in a smoke run), bytes read + written
  const bytes = run.plan.smoke ? 2 ** 22 : 2 ** 28;
  const usage = GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
  const a = gpu.device.createBuffer({ label: 'benchGpu.copyA', size: bytes, usage });
  const b = gpu.device.createBuffer({ label: 'benchGpu.copyB', size: bytes, usage });
  const timer = new BracketTimer(gpu.device);
  await run.warmUp((e) => e.copyBufferToBuffer(a, 0, b, 0, bytes));
  let ms = await repeat(9, () => timer.time((e) => e.copyBufferToBuffer(a, 0, b, 0, bytes)));
  let source: string = timer.source;
  if (!(ms.median > 0)) {
    // a timer coarser than the copy (SwiftShader's): the queue's wall time
    source = 'queue wall time';
    ms = await repeat(9, async () => {
      const enc = gpu.device.createCommandEncoder();
      enc.copyBufferToBuffer(a, 0, b, 0, bytes);
      const t0 = performance.now();
      gpu.device.queue.submit([enc.finish()]);
      await gpu.device.queue.onSubmittedWorkDone();
      return performance.now() - t0;
    });
  }
  timer.destroy();
  a.destroy();
  b.destroy();
  const copyGBps = (2 * bytes) / (ms.median * 1e6);
  console.log(`  copyBufferToBuffer ${bytes} B: ${ms.median.toFixed(3)} ms, ${copyGBps.toFixed(1)} GB/s (read + write; ${source})`);
  run.figure(SECTION, 'copyBufferToBuffer bandwidth (read + write)', copyGBps, 'GB/s');
  run.table({
    title: 'adapter',
    header: ['what', 'value'],
    rows: [
      ['adapter', [gpu.adapter.vendor, gpu.adapter.architecture, gpu.adapter.device, gpu.adapter.description].filter(Boolean).join(' / ')],
      ...(smi ? [['nvidia-smi', smi] as [string, string]] : []),
      ['timestamp-query', gpu.features.timestampQuery ? 'yes' : 'no (times are queue wall times)'],
      [
        'subgroups',
        gpu.features.subgroups ? `yes${sizes?.subgroupMinSize ? ` (sizes ${sizes.subgroupMinSize}..${sizes.subgroupMaxSize})` : ''}` : 'no',
      ],
      ['maxStorageBufferBindingSize', limits.maxStorageBufferBindingSize],
      ['maxBufferSize', limits.maxBufferSize],
      ['maxComputeWorkgroupStorageSize', limits.maxComputeWorkgroupStorageSize],
      ['maxComputeInvocationsPerWorkgroup', limits.maxComputeInvocationsPerWorkgroup],
      ['copy bandwidth GB/s (read + write)', copyGBps],
    ],
  });
  return {
    adapter: infoRecord,
    features,
    limits,
    timestampQuery: gpu.features.timestampQuery,
    subgroups: gpu.features.subgroups,
    subgroupSizes: sizes?.subgroupMinSize ? [sizes.subgroupMinSize, sizes.subgroupMaxSize ?? sizes.subgroupMinSize] : undefined,
    nvidiaSmi: smi,
    copyGBps,
  };
}

const CHROMIUMS = ['/usr/bin/chromium', '/usr/bin/chromium-browser', '/usr/bin/google-chrome', '/opt/google/chrome/chrome'];

/**
 * The page benchmark (bench:paper's browser half) needs a Chromium that
 * reaches this GPU. None is carried to a lent machine: Debian's Chromium and
 * its libraries are larger than everything a device call may carry (64 MiB),
 * and the machine reaches no package registry. Says which, for the record.
 */
export function chromiumAvailability(): { found?: string; reason: string } {
  const found = CHROMIUMS.find((p) => existsSync(p));
  if (found)
    return {
      found,
      reason: `${found} is here; bench:gpu does not drive it (npm run bench:paper does, where Node's npm packages and Playwright are installed)`,
    };
  return {
    reason:
      'no Chromium on this machine (looked for ' +
      CHROMIUMS.join(', ') +
      "); a lent GPU machine reaches no registry and Debian's Chromium with its libraries is larger than the 64 MiB a device call carries, so the page benchmark did not run",
  };
}
