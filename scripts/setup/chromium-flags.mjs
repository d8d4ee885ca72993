#!/usr/bin/env node
// Which Chromium flags give a WebGPU canvas that really draws on this machine.
// The flag set that works depends on the machine's graphics stack (ANGLE on
// Vulkan needs a system Vulkan driver with surface extensions; ANGLE on
// SwiftShader does not: ../shared/docs/TOOLCHAIN.md), so it is probed, not
// assumed: each candidate launches headless Chromium on a tiny page that
// draws a colour with a render pipeline, presents it to a <canvas>, and reads
// the pixels back. The first that draws wins and is cached in .cache/ (keyed
// by Chromium's version, the candidates and the installed Vulkan drivers).
//
//   node scripts/setup/chromium-flags.mjs          probe (or read the cache), print the set
//   node scripts/setup/chromium-flags.mjs --json   print {executablePath, args, env, name} only
//   node scripts/setup/chromium-flags.mjs --fresh  ignore the cache
//   node scripts/setup/chromium-flags.mjs --all    try every candidate and report each (diagnosis)
import { createHash } from 'node:crypto';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:http';
import { join } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const root = fileURLToPath(new URL('../..', import.meta.url));
const CACHE = join(root, '.cache', 'chromium-flags.json');
export const SWIFTSHADER_ICD = '/usr/lib/chromium/vk_swiftshader_icd.json';

const QUIET = ['--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'];
const SOFTWARE_WEBGPU = [
  '--no-sandbox',
  '--enable-unsafe-webgpu',
  '--use-webgpu-adapter=swiftshader',
  '--enable-features=Vulkan',
  '--use-vulkan=swiftshader',
];

/** Tried in this order; the first that presents a frame is used. */
export const CANDIDATES = [
  { name: 'ANGLE on SwiftShader', args: [...SOFTWARE_WEBGPU, '--use-angle=swiftshader', ...QUIET], env: {} },
  { name: 'ANGLE on Vulkan', args: [...SOFTWARE_WEBGPU, '--use-angle=vulkan', ...QUIET], env: {} },
  {
    name: 'ANGLE on Vulkan, SwiftShader as the only Vulkan driver',
    args: [...SOFTWARE_WEBGPU, '--use-angle=vulkan', ...QUIET],
    env: { VK_ICD_FILENAMES: SWIFTSHADER_ICD },
  },
  { name: 'WebGPU on SwiftShader, default ANGLE', args: [...SOFTWARE_WEBGPU, ...QUIET], env: {} },
];

export function chromiumPath() {
  const candidates = [process.env.CHROMIUM_PATH, '/usr/bin/chromium', '/usr/bin/chromium-browser'].filter(Boolean);
  return candidates.find((p) => existsSync(p)) ?? '/usr/bin/chromium';
}

function chromiumVersion(exe) {
  const r = spawnSync(exe, ['--version'], { encoding: 'utf8', timeout: 30_000 });
  return r.status === 0 ? r.stdout.trim() : undefined;
}

function vulkanDrivers() {
  const out = [];
  for (const dir of ['/usr/share/vulkan/icd.d', '/etc/vulkan/icd.d']) {
    try {
      out.push(...readdirSync(dir).map((f) => join(dir, f)));
    } catch {
      // no such folder: no drivers there
    }
  }
  return out.sort();
}

const PAGE = `<!doctype html><canvas id="c" width="64" height="64"></canvas><script type="module">
const WANT = [51, 153, 204];
async function probe() {
  if (!navigator.gpu) return 'navigator.gpu is missing';
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) return 'no WebGPU adapter';
  const device = await adapter.requestDevice();
  const errors = [];
  device.addEventListener('uncapturederror', (e) => errors.push(e.error.message));
  device.lost.then((i) => { if (i.reason !== 'destroyed') errors.push('device lost: ' + i.message); });
  const canvas = document.getElementById('c');
  const ctx = canvas.getContext('webgpu');
  if (!ctx) return 'no webgpu canvas context';
  const format = navigator.gpu.getPreferredCanvasFormat();
  ctx.configure({ device, format, alphaMode: 'opaque' });
  const module = device.createShaderModule({ code: \`
    @vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
      let p = array(vec2f(-1, -1), vec2f(3, -1), vec2f(-1, 3));
      return vec4f(p[i], 0, 1);
    }
    @fragment fn fs() -> @location(0) vec4f { return vec4f(0.2, 0.6, 0.8, 1); }\` });
  const pipeline = device.createRenderPipeline({ layout: 'auto', vertex: { module }, fragment: { module, targets: [{ format }] } });
  // Frames 0-2 are presented (this is where a broken ANGLE/Vulkan set-up
  // fails); frame 3 is read back before it is presented.
  const c2 = document.createElement('canvas');
  c2.width = c2.height = 64;
  const g = c2.getContext('2d');
  for (let frame = 0; frame < 4; frame++) {
    const enc = device.createCommandEncoder();
    const pass = enc.beginRenderPass({ colorAttachments: [{ view: ctx.getCurrentTexture().createView(), loadOp: 'clear', storeOp: 'store', clearValue: [1, 0, 0, 1] }] });
    pass.setPipeline(pipeline);
    pass.draw(3);
    pass.end();
    device.queue.submit([enc.finish()]);
    if (frame === 3) g.drawImage(canvas, 0, 0);
    else await new Promise((r) => requestAnimationFrame(r));
  }
  await device.queue.onSubmittedWorkDone();
  const px = Array.from(g.getImageData(32, 32, 1, 1).data.slice(0, 3));
  if (errors.length) return 'WebGPU error: ' + errors.join('; ');
  if (px.some((v, i) => Math.abs(v - WANT[i]) > 3)) return 'canvas shows rgb(' + px + '), not the drawn rgb(' + WANT + ')';
  return 'ok';
}
probe().then((r) => { window.probeResult = r; }, (e) => { window.probeResult = 'exception: ' + (e && e.message || e); });
</script>`;

function servePage() {
  const server = createServer((_req, res) => {
    res.writeHead(200, { 'Content-Type': 'text/html; charset=utf-8' }).end(PAGE);
  });
  return new Promise((ok, fail) => {
    server.once('error', fail);
    server.listen(0, '127.0.0.1', () => ok(server));
  });
}

async function tryCandidate(chromium, exe, url, candidate) {
  let browser;
  const logs = [];
  try {
    browser = await chromium.launch({
      executablePath: exe,
      args: candidate.args,
      env: { ...process.env, ...candidate.env },
      headless: true,
      timeout: 60_000,
    });
    const page = await browser.newPage();
    page.on('console', (m) => {
      if (m.type() === 'error') logs.push(m.text());
    });
    page.on('pageerror', (e) => logs.push(e.message));
    await page.goto(url, { timeout: 60_000 });
    await page.waitForFunction(() => window.probeResult !== undefined, undefined, { timeout: 60_000 });
    const result = await page.evaluate(() => window.probeResult);
    return result === 'ok' ? 'ok' : [result, ...logs].join('; ');
  } catch (e) {
    return [String(e?.message ?? e).split('\n')[0], ...logs].join('; ');
  } finally {
    await browser?.close().catch(() => undefined);
  }
}

function cacheKey(exe, version) {
  return createHash('sha256')
    .update(JSON.stringify({ exe, version, CANDIDATES, drivers: vulkanDrivers() }))
    .digest('hex');
}

/** The flag set to launch Chromium with: from the cache, else probed now. Throws if none draws. */
export async function chromiumWebGpuLaunch({ fresh = false, all = false, log = (s) => console.error(s) } = {}) {
  const exe = chromiumPath();
  if (!existsSync(exe)) {
    throw new Error(
      `Chromium not found at ${exe}: install Debian's chromium (apt-get install chromium; npm test does it when run as root) or set CHROMIUM_PATH.`,
    );
  }
  const version = chromiumVersion(exe);
  if (!version) throw new Error(`${exe} --version failed: is Chromium installed correctly?`);
  const key = cacheKey(exe, version);
  if (!fresh && existsSync(CACHE)) {
    try {
      const cached = JSON.parse(readFileSync(CACHE, 'utf8'));
      if (cached.key === key) return cached.launch;
    } catch {
      // unreadable cache: probe again
    }
  }
  log(`[setup] probing which Chromium flags draw a WebGPU canvas (${version})...`);
  const { chromium } = await import('@playwright/test');
  const server = await servePage();
  const url = `http://127.0.0.1:${server.address().port}/`;
  const tried = [];
  try {
    for (const candidate of CANDIDATES) {
      const outcome = await tryCandidate(chromium, exe, url, candidate);
      log(`[setup]   ${candidate.name}: ${outcome === 'ok' ? 'draws' : `fails (${outcome.slice(0, 300)})`}`);
      if (outcome === 'ok' && !all) {
        const launch = { name: candidate.name, executablePath: exe, args: candidate.args, env: candidate.env, chromium: version };
        mkdirSync(join(root, '.cache'), { recursive: true });
        writeFileSync(CACHE, JSON.stringify({ key, launch }, null, 2) + '\n');
        return launch;
      }
      tried.push(
        `  ${candidate.name} (${[...candidate.args.filter((a) => !QUIET.includes(a)), ...Object.entries(candidate.env).map(([k, v]) => `${k}=${v}`)].join(' ')}): ${outcome === 'ok' ? 'draws' : outcome.slice(0, 300)}`,
      );
    }
  } finally {
    server.close();
  }
  if (all) return { name: 'diagnosis', tried };
  throw new Error(
    `No Chromium flag set draws a WebGPU canvas with ${exe} (${version}). Tried:\n${tried.join('\n')}\n` +
      `SwiftShader's Vulkan driver (${SWIFTSHADER_ICD}) comes with Debian's chromium package; ` +
      'install or reinstall it and the Vulkan loader and drivers: apt-get install -y chromium libvulkan1 mesa-vulkan-drivers',
  );
}

if (import.meta.url === pathToFileURL(process.argv[1] ?? '').href) {
  const json = process.argv.includes('--json');
  try {
    const launch = await chromiumWebGpuLaunch({ fresh: process.argv.includes('--fresh'), all: process.argv.includes('--all') });
    if (launch.tried) {
      console.log(launch.tried.join('\n'));
      process.exit(0);
    }
    if (json) console.log(JSON.stringify(launch));
    else
      console.log(
        `Chromium flags: ${launch.name} (${launch.chromium})\n  ${launch.args.join(' ')}${Object.keys(launch.env).length ? `\n  env: ${JSON.stringify(launch.env)}` : ''}`,
      );
  } catch (e) {
    console.error(`[setup] ${e.message}`);
    process.exit(1);
  }
}
