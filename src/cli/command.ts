// The shape of a CLI command. Each command lives in src/cli/commands/ and is
// listed in commands/index.ts; main.ts parses options, provides the GPU and
// writes the returned result to `--json FILE`.
import type { ParseArgsConfig } from 'node:util';
import type { GpuContext } from '../gpu/device.ts';

export type OptionSpec = NonNullable<ParseArgsConfig['options']>;

export interface ParsedArgs {
  values: Record<string, string | boolean | string[] | boolean[] | undefined>;
  positionals: string[];
}

export interface CliContext {
  /** The WebGPU device (created on first use; says which adapter on stderr). */
  gpu(): Promise<GpuContext>;
  /** Progress and human-readable output (stderr, so stdout stays clean). */
  log(message: string): void;
}

export interface CliCommand {
  name: string;
  summary: string;
  /** e.g. "info FILE" */
  usage: string;
  options: OptionSpec;
  run(ctx: CliContext, args: ParsedArgs): Promise<unknown>;
}

/** A wrong command line (an unknown option, a missing or malformed argument): printed with the usage, exit code 2. */
export class UsageError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'UsageError';
  }
}

/**
 * A failure of the data or the network: a file that cannot be read or is not
 * what it claims, a store that cannot be reached or is damaged. Printed
 * without the usage (the command line was right), exit code 1.
 */
export class InputError extends Error {
  constructor(message: string, options?: { cause?: unknown }) {
    super(message, options);
    this.name = 'InputError';
  }
}

/**
 * The command ran but did not do all it was asked (e.g. a surface over the
 * memory budget): `result` is still written to --json, the message printed,
 * and the exit status is 1.
 */
export class CommandFailed extends Error {
  constructor(
    message: string,
    readonly result: unknown,
  ) {
    super(message);
    this.name = 'CommandFailed';
  }
}

export function stringOption(args: ParsedArgs, name: string): string | undefined {
  const v = args.values[name];
  return typeof v === 'string' ? v : undefined;
}

export function requiredPositional(args: ParsedArgs, index: number, what: string): string {
  const v = args.positionals[index];
  if (v === undefined) throw new UsageError(`missing ${what}`);
  return v;
}

export function numberOption(args: ParsedArgs, name: string): number | undefined {
  const v = stringOption(args, name);
  if (v === undefined) return undefined;
  const n = Number(v);
  if (!Number.isFinite(n)) throw new UsageError(`--${name} must be a number (got "${v}")`);
  return n;
}

/** Comma-separated numbers, e.g. `--iso 10.5,20,30`. */
export function numberListOption(args: ParsedArgs, name: string): number[] | undefined {
  const v = stringOption(args, name);
  if (v === undefined) return undefined;
  return v.split(',').map((s) => {
    const n = Number(s.trim());
    if (s.trim() === '' || !Number.isFinite(n)) throw new UsageError(`--${name} must be comma-separated numbers (got "${v}")`);
    return n;
  });
}
