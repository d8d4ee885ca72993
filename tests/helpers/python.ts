// Runs the reference tools in the project's .venv (made by `npm test`).
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

export const repoRoot = fileURLToPath(new URL('../..', import.meta.url));
export const sharedData = fileURLToPath(new URL('../../../shared/data/', import.meta.url));

export function venvPython(): string {
  const python = `${repoRoot}.venv/bin/python`;
  if (!existsSync(python)) throw new Error('.venv is missing: run `npm test` once (it installs tests/python-requirements.txt)');
  return python;
}

/** Runs a Python snippet with arguments; returns its stdout. The snippet may import this folder's modules (`from ply import read_ply`). */
export function runPython(code: string, args: string[] = [], timeoutMs = 300_000): string {
  return execFileSync(venvPython(), ['-c', code, ...args], {
    encoding: 'utf8',
    timeout: timeoutMs,
    maxBuffer: 1 << 28,
    env: { ...process.env, PYTHONPATH: [helpersDir, process.env.PYTHONPATH].filter(Boolean).join(':') },
  });
}

const helpersDir = fileURLToPath(new URL('.', import.meta.url));
