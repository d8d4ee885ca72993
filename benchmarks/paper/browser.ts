// The "in the browser" measurements of `npm run bench:paper`: builds the
// benchmark page (paper-bench.html) with Vite into a temporary folder, serves
// it and the benchmark's data files from a small local HTTP server, and
// drives it in headless Chromium (Debian's /usr/bin/chromium through
// Playwright, WebGPU on SwiftShader where there is no GPU) through
// window.paperBench. Every call has a time limit and page errors are reported.
import { createReadStream, existsSync, mkdtempSync, rmSync, statSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import type { AddressInfo } from 'node:net';
import { tmpdir } from 'node:os';
import { extname, join, normalize, resolve, sep } from 'node:path';
import type { Browser, Page } from '@playwright/test';
import type { PaperBenchApi } from '../../src/examples/paper-bench/main.ts';
import { chromiumLaunchOptions, chromiumPath } from '../../tests/e2e/chromium.ts';

const TYPES: Record<string, string> = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.wasm': 'application/wasm',
  '.json': 'application/json',
  '.map': 'application/json',
  '.svg': 'image/svg+xml',
};

function serveFolders(folders: Record<string, string>): Promise<Server> {
  const roots = Object.entries(folders).map(([prefix, dir]) => [prefix, resolve(dir)] as const);
  const server = createServer((req, res) => {
    const url = decodeURIComponent((req.url ?? '/').split('?')[0]);
    for (const [prefix, root] of roots) {
      if (!url.startsWith(prefix)) continue;
      const path = normalize(join(root, url.slice(prefix.length) || 'index.html'));
      if ((path === root || path.startsWith(root + sep)) && existsSync(path) && statSync(path).isFile()) {
        res.writeHead(200, {
          'Content-Type': TYPES[extname(path)] ?? 'application/octet-stream',
          'Content-Length': statSync(path).size,
          'Cache-Control': 'no-store',
        });
        createReadStream(path).pipe(res);
        return;
      }
    }
    res.writeHead(404).end('not found');
  });
  return new Promise((ok, fail) => {
    server.once('error', fail);
    server.listen(0, '127.0.0.1', () => ok(server));
  });
}

async function withTimeout<T>(what: string, ms: number, p: Promise<T>): Promise<T> {
  let timer: NodeJS.Timeout | undefined;
  try {
    return await Promise.race([
      p,
      new Promise<never>((_, reject) => {
        timer = setTimeout(() => reject(new Error(`${what}: no answer from Chromium within ${Math.round(ms / 1000)} s`)), ms);
      }),
    ]);
  } finally {
    clearTimeout(timer);
  }
}

export class BrowserBench {
  private constructor(
    private readonly browser: Browser,
    private readonly page: Page,
    private readonly server: Server,
    private readonly buildDir: string,
    readonly baseUrl: string,
    readonly info: { userAgent: string; hardwareConcurrency: number; webgpu: boolean; chromium: string; flags: string[] },
    private readonly pageErrors: string[],
  ) {}

  /**
   * Builds the page, starts the server and Chromium. `dataDir` is served at
   * /bench-data/. `software`: the machine has no GPU (use SwiftShader's flags).
   */
  static async start(root: string, dataDir: string, software: boolean, log: (s: string) => void): Promise<BrowserBench> {
    const executable = chromiumPath();
    if (!existsSync(executable))
      throw new Error(`Chromium not found at ${executable}: install Debian's chromium (npm test's set-up does) or set CHROMIUM_PATH`);
    const buildDir = mkdtempSync(join(tmpdir(), 'paper-bench-page-'));
    let server: Server | undefined;
    let browser: Browser | undefined;
    try {
      log('building paper-bench.html (vite)...');
      const { build } = await import('vite');
      await build({
        root,
        configFile: false,
        logLevel: 'warn',
        build: {
          outDir: buildDir,
          emptyOutDir: true,
          target: 'es2022',
          sourcemap: false,
          rolldownOptions: { input: { paperBench: join(root, 'paper-bench.html') } },
        },
      });
      server = await serveFolders({ '/bench-data/': dataDir, '/': buildDir });
      const baseUrl = `http://127.0.0.1:${(server.address() as AddressInfo).port}`;
      // No GPU: the flag set probed to draw on SwiftShader on this machine.
      const probed = software ? chromiumLaunchOptions() : undefined;
      if (probed) log(`Chromium flags: ${probed.args.join(' ')}`);
      const flags = probed?.args ?? [
        '--no-sandbox',
        '--enable-unsafe-webgpu',
        '--enable-features=Vulkan',
        '--disable-background-networking',
        '--disable-component-update',
        '--disable-sync',
        '--no-first-run',
      ];
      const { chromium } = await import('@playwright/test');
      browser = await chromium.launch({
        executablePath: probed?.executablePath ?? executable,
        args: flags,
        env: probed?.env,
        headless: true,
        timeout: 120_000,
      });
      const page = await browser.newPage();
      const pageErrors: string[] = [];
      page.on('pageerror', (e) => pageErrors.push(e.message));
      page.on('console', (m) => {
        if (m.type() === 'error') pageErrors.push(m.text());
      });
      await page.goto(`${baseUrl}/paper-bench.html`, { timeout: 120_000 });
      await page.waitForFunction(() => window.paperBench?.version === 1, undefined, { timeout: 120_000 });
      const info = await page.evaluate(() => window.paperBench!.info());
      return new BrowserBench(browser, page, server, buildDir, baseUrl, { ...info, chromium: browser.version(), flags }, pageErrors);
    } catch (e) {
      await browser?.close().catch(() => undefined);
      server?.close();
      rmSync(buildDir, { recursive: true, force: true });
      throw e;
    }
  }

  private async call<K extends Exclude<keyof PaperBenchApi, 'version' | 'info'>>(
    method: K,
    arg: Parameters<PaperBenchApi[K]>[0],
    timeoutMs: number,
  ): Promise<Awaited<ReturnType<PaperBenchApi[K]>>> {
    const before = this.pageErrors.length;
    try {
      return (await withTimeout(
        `paperBench.${method}`,
        timeoutMs,
        this.page.evaluate(({ m, a }) => (window.paperBench as unknown as Record<string, (x: unknown) => Promise<unknown>>)[m](a), {
          m: method as string,
          a: arg as unknown,
        }),
      )) as Awaited<ReturnType<PaperBenchApi[K]>>;
    } catch (e) {
      const extra = this.pageErrors.slice(before);
      throw new Error(`${(e as Error).message.split('\n')[0]}${extra.length ? ` (page errors: ${extra.join('; ')})` : ''}`);
    }
  }

  /** The URL under which `file` (a name in dataDir) is served. */
  dataUrl(file: string): string {
    return `/bench-data/${encodeURIComponent(file)}`;
  }

  serialMc(arg: Parameters<PaperBenchApi['serialMc']>[0], timeoutMs: number) {
    return this.call('serialMc', arg, timeoutMs);
  }

  zfpWasm(arg: Parameters<PaperBenchApi['zfpWasm']>[0], timeoutMs: number) {
    return this.call('zfpWasm', arg, timeoutMs);
  }

  gpuDecode(arg: Parameters<PaperBenchApi['gpuDecode']>[0], timeoutMs: number) {
    return this.call('gpuDecode', arg, timeoutMs);
  }

  naiveMc(arg: Parameters<PaperBenchApi['naiveMc']>[0], timeoutMs: number) {
    return this.call('naiveMc', arg, timeoutMs);
  }

  async close(): Promise<void> {
    await this.browser.close().catch(() => undefined);
    await new Promise((r) => this.server.close(r));
    rmSync(this.buildDir, { recursive: true, force: true });
  }
}
