// Headless runner: `npm run cli -- <command> [options]`. Runs the same
// TypeScript/WGSL modules as the page, on Dawn (a GPU, or SwiftShader).
import { writeFileSync } from 'node:fs';
import { parseArgs } from 'node:util';
import { describeAdapter, WebGpuUnavailableError, type GpuContext } from '../gpu/device.ts';
import { requestNodeGpu } from '../gpu/node-gpu.ts';
import { CommandFailed, InputError, UsageError, type CliCommand, type CliContext, type ParsedArgs } from './command.ts';
import { commands } from './commands/index.ts';

function usage(): string {
  const lines = ['usage: npm run cli -- <command> [options] [--json FILE]', '', 'commands:'];
  for (const c of commands) lines.push(`  ${c.usage.padEnd(44)} ${c.summary}`);
  lines.push('', 'Every command accepts --json FILE (results as JSON). ZFPISO_ADAPTER=auto|gpu|swiftshader picks the adapter.');
  return lines.join('\n');
}

function makeContext(): CliContext & { dispose(): void } {
  let gpu: Promise<GpuContext> | undefined;
  return {
    gpu() {
      gpu ??= requestNodeGpu({
        label: 'cli.device',
        onFailure: (f) => {
          console.error(`error: WebGPU ${f.kind}: ${f.message}`);
          process.exit(1);
        },
      }).then((ctx) => {
        console.error(`adapter: ${describeAdapter(ctx.adapter)}`);
        return ctx;
      });
      return gpu;
    },
    log(message: string) {
      console.error(message);
    },
    dispose() {
      void gpu?.then((g) => g.device.destroy());
    },
  };
}

async function main(argv: string[]): Promise<number> {
  const [name, ...rest] = argv;
  if (!name || name === '--help' || name === '-h' || name === 'help') {
    console.log(usage());
    return name ? 0 : 2;
  }
  const command: CliCommand | undefined = commands.find((c) => c.name === name);
  if (!command) {
    console.error(`error: unknown command "${name}"\n\n${usage()}`);
    return 2;
  }
  let args: ParsedArgs;
  try {
    args = parseArgs({
      args: rest,
      options: { ...command.options, json: { type: 'string' }, help: { type: 'boolean', short: 'h' } },
      allowPositionals: true,
      strict: true,
    }) as ParsedArgs;
  } catch (e) {
    console.error(`error: ${(e as Error).message}\nusage: npm run cli -- ${command.usage}`);
    return 2;
  }
  if (args.values.help) {
    console.log(`usage: npm run cli -- ${command.usage}\n${command.summary}`);
    return 0;
  }
  const ctx = makeContext();
  const writeJson = (result: unknown) => {
    const json = args.values.json;
    if (typeof json === 'string') {
      writeFileSync(json, JSON.stringify(result, null, 2) + '\n');
      ctx.log(`wrote ${json}`);
    }
  };
  try {
    writeJson(await command.run(ctx, args));
    return 0;
  } catch (e) {
    if (e instanceof CommandFailed) {
      writeJson(e.result);
      console.error(`error: ${e.message}`);
      return 1;
    }
    if (e instanceof UsageError) {
      console.error(`error: ${e.message}\nusage: npm run cli -- ${command.usage}`);
      return 2;
    }
    if (e instanceof InputError || e instanceof WebGpuUnavailableError) {
      console.error(`error: ${e.message}`);
      return 1;
    }
    const err = e as Error;
    console.error(`error: ${err.message}`);
    if (process.env.ZFPISO_DEBUG) console.error(err.stack);
    return 1;
  } finally {
    ctx.dispose();
  }
}

main(process.argv.slice(2)).then(
  (code) => process.exit(code),
  (e) => {
    console.error(e);
    process.exit(1);
  },
);
