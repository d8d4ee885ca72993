// A CPU stand-in for the GPU isosurface, for renderer tests: serial marching
// cubes (src/mc) packed into the compressed vertex format, and every block
// "cached" (slot = block id), so SurfaceLayer can be tested without the
// pipeline. Not a product path.
import type { IsosurfaceDrawData } from '../../isosurface/types.ts';
import { marchingCubes } from '../../mc/serial-mc.ts';
import type { Dims } from '../../core/naming.ts';

/** Packs a triangle soup (voxel coordinates) into u32 pairs (position in its cell's block, block id). */
export function packTriangleSoup(positions: Float32Array, dims: Dims): Uint32Array {
  const grid = dims.map((n) => Math.ceil(n / 4));
  const out = new Uint32Array((positions.length / 3) * 2);
  for (let t = 0; t < positions.length; t += 9) {
    // The triangle's cell: the floor of its smallest corner, per axis.
    const cell = [0, 1, 2].map((a) => Math.min(dims[a] - 2, Math.floor(Math.min(positions[t + a], positions[t + 3 + a], positions[t + 6 + a]))));
    const block = cell.map((c) => c >> 2);
    const id = block[0] + grid[0] * (block[1] + grid[1] * block[2]);
    for (let v = 0; v < 3; v++) {
      let packed = 0;
      for (let a = 0; a < 3; a++) {
        const local = positions[t + 3 * v + a] - 4 * block[a];
        const q = Math.min(1023, Math.max(0, Math.round((local * 1023) / 4)));
        packed |= q << (10 * a);
      }
      const i = (t / 9) * 6 + 2 * v;
      out[i] = packed >>> 0;
      out[i + 1] = id;
    }
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

export function createCpuSurface(device: GPUDevice, values: Float32Array, dims: Dims, iso: number): CpuSurface {
  const mc = marchingCubes(values, dims, iso);
  const packed = packTriangleSoup(mc.positions, dims);
  const blockGrid = dims.map((n) => Math.ceil(n / 4)) as Dims;
  const blockCount = blockGrid[0] * blockGrid[1] * blockGrid[2];
  const make = (label: string, data: ArrayBufferView, usage: number) => {
    const buffer = device.createBuffer({ label, size: Math.max(16, Math.ceil(data.byteLength / 4) * 4), usage: usage | GPUBufferUsage.COPY_DST });
    if (data.byteLength > 0) device.queue.writeBuffer(buffer, 0, data.buffer, data.byteOffset, data.byteLength);
    return buffer;
  };
  const vertices = make('CpuSurface.vertices', packed, GPUBufferUsage.VERTEX | GPUBufferUsage.STORAGE);
  const drawArgs = make('CpuSurface.drawArgs', new Uint32Array([mc.triangleCount * 3, 1, 0, 0]), GPUBufferUsage.INDIRECT | GPUBufferUsage.STORAGE);
  const slotData = make('CpuSurface.slotData', blocksOf(values, dims), GPUBufferUsage.STORAGE);
  const blockToSlot = make('CpuSurface.blockToSlot', Uint32Array.from({ length: blockCount }, (_, i) => i), GPUBufferUsage.STORAGE);
  let lo = Infinity, hi = -Infinity;
  for (const v of values) {
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return {
    triangles: mc.triangleCount,
    data: {
      shards: [{ vertices, drawArgs, drawArgsOffset: 0 }],
      info: { dims, blockGrid, blockCount, valueRange: [lo, hi] },
      slotData,
      blockToSlot,
      version: 0,
    },
    destroy() {
      for (const b of [vertices, drawArgs, slotData, blockToSlot]) b.destroy();
    },
  };
}
