import { openSync, readSync, closeSync, statSync } from 'node:fs';
import { basename } from 'node:path';
import { describeFile } from '../../formats/describe.ts';
import { requiredPositional, numberOption, type CliCommand } from '../command.ts';

/** First bytes of a file, for signatures and headers. */
function readHead(path: string, length: number): Uint8Array {
  const fd = openSync(path, 'r');
  try {
    const head = new Uint8Array(length);
    const n = readSync(fd, head, 0, length, 0);
    return head.subarray(0, n);
  } finally {
    closeSync(fd);
  }
}

export const infoCommand: CliCommand = {
  name: 'info',
  summary: 'file kind, dims, dtype; for zfp the mode, rate and header presence',
  usage: 'info FILE [--rate R]',
  options: { rate: { type: 'string' } },
  async run(_ctx, args) {
    const path = requiredPositional(args, 0, 'FILE');
    const size = statSync(path).size;
    const description = describeFile(basename(path), size, readHead(path, 4096), { rate: numberOption(args, 'rate') });
    for (const [k, v] of Object.entries(description)) {
      if (v === undefined) continue;
      console.log(`${k.padEnd(14)} ${typeof v === 'object' ? JSON.stringify(v) : String(v)}`);
    }
    return { file: path, ...description };
  },
};
