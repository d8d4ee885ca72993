// Every CLI command, in the order `--help` lists them.
import type { CliCommand } from '../command.ts';
import { benchCommand } from './bench.ts';
import { compressCommand } from './compress.ts';
import { decompressCommand } from './decompress.ts';
import { extractCommand } from './extract.ts';
import { gpuInfoCommand } from './gpu-info.ts';
import { infoCommand } from './info.ts';
import { lasCommand } from './las.ts';
import { renderCommand } from './render.ts';
import { tiffCommand } from './tiff.ts';

export const commands: CliCommand[] = [
  infoCommand,
  compressCommand,
  decompressCommand,
  extractCommand,
  renderCommand,
  benchCommand,
  gpuInfoCommand,
  lasCommand,
  tiffCommand,
];
