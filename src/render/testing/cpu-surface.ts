// A CPU stand-in for the GPU isosurface, for renderer tests: serial marching
// cubes (src/mc) packed into the compressed vertex format, and every block
// "cached" (slot = block id), so SurfaceLayer can be tested without the
// pipeline. Not a product path.
import type { IsosurfaceDrawData } from '../../isosurface/types.ts';
import { encodeVertexEdge } from '../../isosurface/vertex-format.ts';
import { marchingCubes } from '../../mc/serial-mc.ts';
import type { Dims } from '../../core/naming.ts';

/** Packs a triangle soup (voxel coordinates) into the position words of the vertex format (edge and fraction; block coordinates), 2 u32 per corner. */
export function packTriangleSoup(positions: Float32Array, dims: Dims): Uint32Array {
  const out = new Uint32Array((positions.length / 3) * 2);
  const corner: [number, number, number] = [0, 0, 0];
  for (let t = 0; t < positions.length; t += 9) {
    // The triangle's cell: the floor of its smallest corner, per axis; its block places the vertices.
    const cell = [0, 1, 2].map((a) =>
      Math.min(dims[a] - 2, Math.floor(Math.min(positions[t + a], positions[t + 3 + a], positions[t + 6 + a]))),
    );
    const block = cell.map((c) => c >> 2) as [number, number, number];
    for (let v = 0; v < 3; v++) {
      const p = positions.subarray(t + 3 * v, t + 3 * v + 3);
      // the vertex's edge: along the axis whose coordinate is farthest from a whole number
      let axis = 0;
      let best = -1;
      for (let a = 0; a < 3; a++) {
        const f = p[a] - Math.floor(p[a]);
        if (Math.min(f, 1 - f) > best) {
          best = Math.min(f, 1 - f);
          axis = a;
        }
      }
      for (let a = 0; a < 3; a++) corner[a] = Math.min(4, Math.max(0, (a === axis ? Math.floor(p[a]) : Math.round(p[a])) - 4 * block[a]));
      const [w0, w1] = encodeVertexEdge(corner, axis, p[axis] - Math.floor(p[axis]), block, dims);
      const i = (t / 9) * 6 + 2 * v;
      out[i] = w0;
      out[i + 1] = w1;
    }
  }
  return out;
}

/**
 * Per vertex of a soup (voxel coordinates), the outward normal (minus the
 * volume gradient) the pipeline writes (block_emit.wgsl), computed on the
 * CPU: central differences at both ends of the vertex's grid edge (the axis
 * whose coordinate is farthest from a whole number), interpolated at the
 * vertex; a neighbour outside the volume or in a block `readable` rejects
 * gives a one-sided difference. Unnormalized.
 */
export function soupNormals(
  values: Float32Array,
  dims: Dims,
  positions: Float32Array,
  readable: (block: number) => boolean = () => true,
): Float32Array {
  const [nx, ny, nz] = dims;
  const grid = dims.map((n) => Math.ceil(n / 4));
  const voxel = (x: number, y: number, z: number): number | undefined => {
    if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) return undefined;
    if (!readable((x >> 2) + grid[0] * ((y >> 2) + grid[1] * (z >> 2)))) return undefined;
    return values[x + nx * (y + ny * z)];
  };
  const gradient = (g: number[]): number[] => {
    const c = voxel(g[0], g[1], g[2]);
    return [0, 1, 2].map((a) => {
      const p = [...g];
      const m = [...g];
      p[a]++;
      m[a]--;
      const vp = voxel(p[0], p[1], p[2]);
      const vm = voxel(m[0], m[1], m[2]);
      if (vp !== undefined && vm !== undefined) return 0.5 * (vp - vm);
      if (c === undefined) return 0;
      if (vp !== undefined) return vp - c;
      if (vm !== undefined) return c - vm;
      return 0;
    });
  };
  const out = new Float32Array(positions.length);
  for (let i = 0; i < positions.length; i += 3) {
    const p = [positions[i], positions[i + 1], positions[i + 2]];
    const d = p.map((x) => Math.abs(x - Math.round(x)));
    const axis = d[1] > d[0] && d[1] >= d[2] ? 1 : d[2] > d[0] && d[2] > d[1] ? 2 : 0;
    const t = p[axis] - Math.floor(p[axis]);
    const g0 = p.map((x, a) => (a === axis ? Math.floor(x) : Math.round(x)));
    const g1 = g0.map((x, a) => (a === axis ? x + 1 : x));
    const a0 = gradient(g0);
    const a1 = gradient(g1);
    for (let a = 0; a < 3; a++) out[i + a] = -(a0[a] + t * (a1[a] - a0[a]));
  }
  return out;
}

/** Octahedral encoding of normals (vertex_format.wgsl encode_vertex_normal): u32 per vertex, 0 = none. */
export function encodeNormals(normals: Float32Array): Uint32Array {
  const out = new Uint32Array(normals.length / 3);
  for (let i = 0; i < out.length; i++) {
    const [x, y, z] = [normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]];
    const l1 = Math.abs(x) + Math.abs(y) + Math.abs(z);
    if (!(l1 > 1e-30)) continue;
    let o = [x / l1, y / l1];
    if (z < 0) o = [(1 - Math.abs(o[1])) * (o[0] >= 0 ? 1 : -1), (1 - Math.abs(o[0])) * (o[1] >= 0 ? 1 : -1)];
    const q = o.map((v) => Math.round((Math.min(1, Math.max(-1, v)) * 0.5 + 0.5) * 65534) + 1);
    out[i] = (q[0] | (q[1] << 16)) >>> 0;
  }
  return out;
}

/** Every block's 64 values (x + 4y + 16z), zero outside the volume. */
export function blocksOf(values: Float32Array, dims: Dims): Float32Array {
  const [nx, ny, nz] = dims;
  const [gx, gy, gz] = dims.map((n) => Math.ceil(n / 4));
  const out = new Float32Array(gx * gy * gz * 64);
  for (let z = 0; z < nz; z++)
    for (let y = 0; y < ny; y++)
      for (let x = 0; x < nx; x++) {
        const b = (x >> 2) + gx * ((y >> 2) + gy * (z >> 2));
        out[b * 64 + (x & 3) + 4 * (y & 3) + 16 * (z & 3)] = values[x + nx * (y + ny * z)];
      }
  return out;
}

export interface CpuSurface {
  data: IsosurfaceDrawData;
  triangles: number;
  destroy(): void;
}

/** `readable`: blocks whose voxels the normals may use (default all; the pipeline reads only cached blocks). */
export function createCpuSurface(
  device: GPUDevice,
  values: Float32Array,
  dims: Dims,
  iso: number,
  readable?: (block: number) => boolean,
): CpuSurface {
  const mc = marchingCubes(values, dims, iso);
  const packed = packTriangleSoup(mc.positions, dims);
  const normals = encodeNormals(soupNormals(values, dims, mc.positions, readable));
  const blockGrid = dims.map((n) => Math.ceil(n / 4)) as Dims;
  const blockCount = blockGrid[0] * blockGrid[1] * blockGrid[2];
  const make = (label: string, data: ArrayBufferView, usage: number) => {
    const buffer = device.createBuffer({
      label,
      size: Math.max(16, Math.ceil(data.byteLength / 4) * 4),
      usage: usage | GPUBufferUsage.COPY_DST,
    });
    if (data.byteLength > 0) device.queue.writeBuffer(buffer, 0, data.buffer, data.byteOffset, data.byteLength);
    return buffer;
  };
  // Drawn as the pipeline draws: 12-byte vertices (position pair, normal), one index per corner.
  const corners = mc.triangleCount * 3;
  const interleaved = new Uint32Array(3 * corners);
  for (let i = 0; i < corners; i++) {
    interleaved[3 * i] = packed[2 * i];
    interleaved[3 * i + 1] = packed[2 * i + 1];
    interleaved[3 * i + 2] = normals[i];
  }
  const vertices = make('CpuSurface.vertices', interleaved, GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE);
  const indices = make(
    'CpuSurface.indices',
    Uint32Array.from({ length: corners }, (_, i) => i),
    GPUBufferUsage.INDEX,
  );
  const drawArgs = make('CpuSurface.drawArgs', new Uint32Array([corners, 1, 0, 0, 0]), GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE);
  const slotData = make('CpuSurface.slotData', blocksOf(values, dims), GPUBufferUsage.STORAGE);
  const blockToSlot = make(
    'CpuSurface.blockToSlot',
    Uint32Array.from({ length: blockCount }, (_, i) => i),
    GPUBufferUsage.STORAGE,
  );
  let lo = Infinity,
    hi = -Infinity;
  for (const v of values) {
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return {
    triangles: mc.triangleCount,
    data: {
      vertices,
      shards: [{ indices, drawArgs, drawArgsOffset: 0 }],
      info: { dims, blockGrid, blockCount, valueRange: [lo, hi] },
      slotData,
      blockToSlot,
      version: 0,
    },
    destroy() {
      for (const b of [vertices, indices, drawArgs, slotData, blockToSlot]) b.destroy();
    },
  };
}
