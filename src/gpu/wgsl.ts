// WGSL sources are plain `.wgsl` files under shaders/, imported as text with
// `?raw` (Vite in the page and tests, scripts/node-hooks.mjs in the CLI).
// Shared snippets are composed explicitly: a kernel lists what it needs.

export interface WgslPart {
  /** Name shown in compile errors (usually the file path). */
  name: string;
  code: string;
}

/** Concatenates snippets in order, with a marker line before each. */
export function composeWgsl(...parts: WgslPart[]): string {
  return parts.map((p) => `// ---- ${p.name} ----\n${p.code.trimEnd()}\n`).join('\n');
}

/** Maps a line of the composed source back to the part it came from. */
export function locateLine(parts: WgslPart[], line: number): { name: string; line: number } {
  let start = 1;
  for (const p of parts) {
    const n = p.code.trimEnd().split('\n').length + 2; // marker + code + blank
    if (line < start + n) return { name: p.name, line: Math.max(1, line - start) };
    start += n;
  }
  return { name: '?', line };
}

export class WgslCompileError extends Error {
  constructor(label: string, details: string) {
    super(`WGSL compilation failed for ${label}:\n${details}`);
    this.name = 'WgslCompileError';
  }
}

/**
 * Creates a shader module and rejects with the compiler's messages (mapped to
 * the snippet files) if it has errors, instead of leaving a silent invalid
 * module. Compute pipelines come from pipeline-cache.ts (per device, shared).
 */
export async function createShaderModule(
  device: GPUDevice,
  label: string,
  parts: WgslPart[],
  code = composeWgsl(...parts),
): Promise<GPUShaderModule> {
  const module = device.createShaderModule({ label, code });
  const info = await module.getCompilationInfo();
  const errors = info.messages.filter((m) => m.type === 'error');
  if (errors.length > 0) {
    const details = errors
      .map((m) => {
        const where = locateLine(parts, m.lineNum);
        return `  ${where.name}:${where.line}:${m.linePos}: ${m.message}`;
      })
      .join('\n');
    throw new WgslCompileError(label, details);
  }
  return module;
}
