// Runs the tests one bundled test file registered (vitest-shim.ts) and prints
// one line per test, then `WGPU-RESULT {"passed":N,"failed":N}` for
// scripts/test-wgpu.mjs.
import { registered } from './vitest-shim.ts';

function withTimeout(p: Promise<unknown>, ms: number): Promise<unknown> {
  let timer: ReturnType<typeof setTimeout> | undefined;
  return Promise.race([
    p,
    new Promise((_, reject) => {
      timer = setTimeout(() => reject(new Error(`timed out after ${ms / 1000} s`)), ms);
    }),
  ]).finally(() => clearTimeout(timer));
}

export async function runRegistered(file: string): Promise<void> {
  let passed = 0;
  let failed = 0;
  const hooksRun = new Set<unknown>();
  try {
    for (const t of registered) {
      if (!hooksRun.has(t.file)) {
        hooksRun.add(t.file);
        for (const h of t.file.beforeAll) await h();
      }
      const start = performance.now();
      try {
        await withTimeout(Promise.resolve().then(t.fn), t.timeoutMs * 3);
        passed++;
        console.log(`  ✓ ${file} > ${t.name} (${Math.round(performance.now() - start)} ms)`);
      } catch (e) {
        failed++;
        console.log(
          `  ✗ ${file} > ${t.name}\n      ${String((e as Error)?.stack ?? e)
            .split('\n')
            .slice(0, 16)
            .join('\n      ')}`,
        );
      }
    }
    for (const t of registered.filter((r, i, all) => all.findIndex((x) => x.file === r.file) === i)) {
      for (const h of t.file.afterAll) await h();
    }
  } catch (e) {
    failed++;
    console.log(`  ✗ ${file}: hook failed: ${(e as Error)?.message ?? e}`);
  }
  if (registered.length === 0) {
    failed++;
    console.log(`  ✗ ${file}: no tests registered`);
  }
  console.log(`WGPU-RESULT ${JSON.stringify({ passed, failed })}`);
}
