// Shared by the marching-cubes tests: the reference figures (shared/data/reference/mc.json),
// the volumes they were computed from, and the Python reference tools in .venv
// (tools/mc/mc-reference.py: zfpy decode, VTK soups).
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { mulberry32 } from '../../../src/util/random.ts';

export const ROOT = fileURLToPath(new URL('../../../', import.meta.url));
export const SHARED_DATA = join(ROOT, '..', 'shared', 'data');

export interface VtkFigures {
  triangles: number;
  points: number;
  area: number;
  degenerate_triangles: number;
  bbox: { min: [number, number, number]; max: [number, number, number] } | null;
}

export interface McIsosurface {
  iso_nominal: number;
  iso: number;
  crossed_edges: number;
  active_cells: number;
  vtkMarchingCubes: VtkFigures;
  vtkFlyingEdges3D: VtkFigures;
}

export interface McVolume {
  file: string;
  file_sha256: string;
  dims_xyz: [number, number, number];
  kind: 'raw' | 'zfp-with-header' | 'zfp-headerless-fixed-precision-8';
  dtype: string;
  decoded_sha256?: string;
  isosurfaces: McIsosurface[];
}

export function loadMcReference(): { volumes: McVolume[] } {
  return JSON.parse(readFileSync(join(SHARED_DATA, 'reference', 'mc.json'), 'utf8'));
}

export function venvPython(): string {
  const python = join(ROOT, '.venv', 'bin', 'python');
  if (!existsSync(python)) {
    throw new Error(`${python} is missing: run \`npm test\` once (it installs tests/python-requirements.txt into .venv)`);
  }
  return python;
}

/** Runs tools/mc/mc-reference.py with the .venv python; returns its JSON answer. */
export function runReferenceTool(args: string[]): any {
  const out = execFileSync(venvPython(), [join(ROOT, 'tools', 'mc', 'mc-reference.py'), ...args], {
    encoding: 'utf8',
    maxBuffer: 1 << 26,
  });
  return JSON.parse(out);
}

export function sha256(data: ArrayBufferView): string {
  return createHash('sha256')
    .update(new Uint8Array(data.buffer, data.byteOffset, data.byteLength))
    .digest('hex');
}

export function asFloat32(bytes: Buffer): Float32Array {
  // Copy: a Buffer's offset need not be 4-aligned.
  const copy = new Uint8Array(bytes.byteLength);
  copy.set(bytes);
  return new Float32Array(copy.buffer);
}

/**
 * The float32 field that mc.json's figures were computed from: raw float32 as is,
 * uint8 converted exactly, zfp streams decoded by zfpy (into `cacheDir`). Checks the
 * file hash and, for zfp, the decoded hash.
 */
export function loadMcVolume(v: McVolume, cacheDir: string): Float32Array {
  const path = join(SHARED_DATA, v.file);
  const bytes = readFileSync(path);
  const fileHash = createHash('sha256').update(bytes).digest('hex');
  if (fileHash !== v.file_sha256) throw new Error(`${v.file}: sha256 ${fileHash}, mc.json says ${v.file_sha256}`);
  const [nx, ny, nz] = v.dims_xyz;
  let data: Float32Array;
  if (v.kind === 'raw') {
    if (v.dtype === 'float32') data = asFloat32(bytes);
    else if (v.dtype === 'uint8') data = Float32Array.from(bytes);
    else throw new Error(`${v.file}: unexpected dtype ${v.dtype}`);
  } else {
    const out = join(cacheDir, v.file.replace(/[^A-Za-z0-9._-]/g, '_') + '.f32');
    const args = ['decode', path, out];
    if (v.kind === 'zfp-headerless-fixed-precision-8') args.push('--precision', '8', '--dims', `${nx}`, `${ny}`, `${nz}`);
    const answer = runReferenceTool(args);
    if (answer.dims.join() !== v.dims_xyz.join()) throw new Error(`${v.file}: decoded dims ${answer.dims}`);
    data = asFloat32(readFileSync(out));
    const h = sha256(data);
    if (h !== answer.sha256 || (v.decoded_sha256 && h !== v.decoded_sha256)) {
      throw new Error(`${v.file}: decoded sha256 ${h}, mc.json says ${v.decoded_sha256}`);
    }
  }
  if (data.length !== nx * ny * nz) throw new Error(`${v.file}: ${data.length} values for ${v.dims_xyz.join('x')}`);
  return data;
}

/** Deterministic pseudo-random numbers in [0, 1) (mulberry32). */
export const rng = mulberry32;
