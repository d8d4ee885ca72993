import { defineConfig } from '@playwright/test';
import { chromiumPath, chromiumWebGpuArgs } from './tests/e2e/chromium.ts';

// End-to-end tests of the built page in Debian's headless Chromium, with
// WebGPU on SwiftShader (flags: ../shared/docs/TOOLCHAIN.md).
export default defineConfig({
  testDir: 'tests/e2e',
  testMatch: '**/*.spec.ts',
  timeout: 180_000,
  expect: { timeout: 60_000 },
  workers: 1,
  outputDir: 'test-results/e2e',
  reporter: [['list']],
  use: {
    baseURL: 'http://127.0.0.1:4173',
    screenshot: 'only-on-failure',
    trace: 'off',
    launchOptions: { executablePath: chromiumPath(), args: chromiumWebGpuArgs },
    viewport: { width: 1100, height: 720 },
  },
  webServer: {
    command: 'npx vite build --logLevel warn && npx vite preview --host 127.0.0.1 --port 4173 --strictPort',
    url: 'http://127.0.0.1:4173',
    reuseExistingServer: false,
    timeout: 180_000,
    stdout: 'ignore',
    stderr: 'pipe',
  },
});
