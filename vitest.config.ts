import { defineConfig } from 'vitest/config';

// Unit tests run in Node on Dawn (the `webgpu` package): the same WebGPU
// implementation as Chrome, the same modules as the CLI, and no browser start
// per file. The page itself is tested with Playwright (tests/e2e).
export default defineConfig({
  test: {
    include: ['tests/unit/**/*.test.ts', 'tests/fuzz/**/*.test.ts'],
    environment: 'node',
    pool: 'forks',
    // SwiftShader runs on the CPU; two cores here.
    maxWorkers: 2,
    testTimeout: 300_000,
    hookTimeout: 120_000,
    reporters: ['default'],
  },
});
