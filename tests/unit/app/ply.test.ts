// The PLY export: packed vertices decode to the positions marching cubes
// made (within the 16-bit quantization along the edge), and an indexed
// mesh's file reads back as written. (The GPU's welded mesh itself: behaviour.test.ts.)
import { describe, expect, it } from 'vitest';
import { encodePly, parsePly, soupOf } from '../../../src/mc/ply.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { packTriangleSoup } from '../../../src/render/testing/cpu-surface.ts';
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

  it('decodes packed vertices to within the quantization step', () => {
    const soup = decodeVertices(packed, packed.length / 2, 2);
    expect(soup.length).toBe(mc.positions.length);
    let worst = 0;
    for (let i = 0; i < soup.length; i++) worst = Math.max(worst, Math.abs(soup[i] - mc.positions[i]));
    expect(worst).toBeLessThanOrEqual(0.5 / 65535 + 2e-6);
  });

  it('writes binary little-endian PLY that reads back exactly', () => {
    const soup = decodeVertices(packed, packed.length / 2, 2);
    // An indexed mesh: the soup's corners as vertices, listed in reverse.
    const corners = soup.length / 3;
    const positions = new Float32Array(soup.length);
    const indices = new Uint32Array(corners);
    for (let i = 0; i < corners; i++) {
      positions.set(soup.subarray(3 * i, 3 * i + 3), 3 * (corners - 1 - i));
      indices[i] = corners - 1 - i;
    }
    const mesh = { positions, indices };
    expect(soupOf(positions, indices)).toEqual(soup);
    const bytes = encodePly(mesh, ['sphere at 7.3']);
    const header = new TextDecoder().decode(bytes.subarray(0, 300));
    expect(header).toContain('format binary_little_endian 1.0');
    expect(header).toContain(`element vertex ${corners}`);
    expect(header).toContain(`element face ${mc.triangleCount}`);
    expect(header).toContain('property list uchar int vertex_indices');
    const back = parsePly(bytes);
    expect(back.comments).toEqual(['sphere at 7.3']);
    expect(back.positions).toEqual(mesh.positions);
    expect(back.indices).toEqual(mesh.indices);
  });
});
