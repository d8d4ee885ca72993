// The PLY export: packed vertices decode to the positions marching cubes
// made (within the 10-bit quantization), welding keeps every triangle and
// merges shared corners, and the file reads back as written.
import { describe, expect, it } from 'vitest';
import { encodePly, parsePly, weldVertices } from '../../../src/mc/ply.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { packTriangleSoup } from '../../../src/render/testing/cpu-surface.ts';
import { generateDefaultVolume } from '../../../src/volume/procedural.ts';
import type { Dims } from '../../../src/core/naming.ts';

function sphere(n: number): Float32Array {
  const v = new Float32Array(n * n * n);
  const c = (n - 1) / 2;
  for (let z = 0; z < n; z++)
    for (let y = 0; y < n; y++) for (let x = 0; x < n; x++) v[x + n * (y + n * z)] = Math.hypot(x - c, y - c, z - c);
  return v;
}

describe('PLY export', () => {
  const dims: Dims = [21, 21, 21];
  const values = sphere(21);
  const mc = marchingCubes(values, dims, 7.3);
  const packed = packTriangleSoup(mc.positions, dims);
  const grid: Dims = [6, 6, 6];

  it('decodes packed vertices to within the quantization step', () => {
    const soup = decodeVertices(packed, packed.length / 2, { blockGrid: grid });
    expect(soup.length).toBe(mc.positions.length);
    let worst = 0;
    for (let i = 0; i < soup.length; i++) worst = Math.max(worst, Math.abs(soup[i] - mc.positions[i]));
    expect(worst).toBeLessThanOrEqual(2 / 1023 + 1e-6);
  });

  it('welds a closed surface into a mesh with V - E + F = 2', () => {
    const soup = decodeVertices(packed, packed.length / 2, { blockGrid: grid });
    const mesh = weldVertices(soup);
    expect(mesh.indices.length).toBe(soup.length / 3);
    const v = mesh.positions.length / 3;
    const f = mesh.indices.length / 3;
    const edges = new Set<string>();
    for (let t = 0; t < f; t++) {
      for (let k = 0; k < 3; k++) {
        const a = mesh.indices[3 * t + k],
          b = mesh.indices[3 * t + ((k + 1) % 3)];
        edges.add(a < b ? `${a},${b}` : `${b},${a}`);
      }
    }
    // A sphere: every vertex copy was merged (else the Euler characteristic is off).
    expect(v - edges.size + f).toBe(2);
    // Every welded vertex equals the soup vertices that map to it.
    for (let i = 0; i < soup.length / 3; i++) {
      const u = mesh.indices[i];
      for (let a = 0; a < 3; a++) expect(mesh.positions[3 * u + a]).toBe(soup[3 * i + a]);
    }
  });

  it('writes binary little-endian PLY that reads back exactly', () => {
    const soup = decodeVertices(packed, packed.length / 2, { blockGrid: grid });
    const mesh = weldVertices(soup);
    const bytes = encodePly(mesh, ['sphere at 7.3']);
    const header = new TextDecoder().decode(bytes.subarray(0, 300));
    expect(header).toContain('format binary_little_endian 1.0');
    expect(header).toContain(`element vertex ${mesh.positions.length / 3}`);
    expect(header).toContain(`element face ${mc.triangleCount}`);
    expect(header).toContain('property list uchar int vertex_indices');
    const back = parsePly(bytes);
    expect(back.comments).toEqual(['sphere at 7.3']);
    expect(back.positions).toEqual(mesh.positions);
    expect(back.indices).toEqual(mesh.indices);
  });

  it('handles the built-in volume (many blocks, open surface)', () => {
    const vol = generateDefaultVolume([48, 40, 36]);
    const m = marchingCubes(vol.data, vol.dims, 0.5);
    const p = packTriangleSoup(m.positions, vol.dims);
    const soup = decodeVertices(p, p.length / 2, { blockGrid: [12, 10, 9] });
    const mesh = weldVertices(soup);
    expect(mesh.indices.length / 3).toBe(m.triangleCount);
    // Most soup vertices are shared by several triangles.
    expect(mesh.positions.length / 3).toBeLessThan(soup.length / 3 / 4);
  });
});
