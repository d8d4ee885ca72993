import { describe, expect } from 'vitest';
import { ExclusiveScan } from '../../../src/primitives/scan.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { SMALL_SIZES, cpuExclusiveScan, diff, gpuCount, poison, randomU32, read, upload } from './helpers.ts';

describe('ExclusiveScan', () => {
  gpuTest('small sizes, GPU count below the buffer length', async ({ gpu }) => {
    const { device } = gpu;
    const scan = await ExclusiveScan.create(device, { capacity: 70000 });
    const problems: string[] = [];
    for (const n of SMALL_SIZES) {
      const extra = 37;
      const data = randomU32(n + extra, n + 1);
      const input = upload(device, 'in', data);
      const output = upload(device, 'out', new Uint32Array(0), n + extra);
      const count = gpuCount(device, n);
      const total = upload(device, 'total', new Uint32Array(0), 3);
      const enc = device.createCommandEncoder();
      scan.encode(enc, { input, output, count, totalOut: { buffer: total, offset: 4 } });
      device.queue.submit([enc.finish()]);
      const ref = cpuExclusiveScan(data, n);
      const d = diff(await read(device, output), ref.scan);
      if (d) problems.push(`n=${n}: ${d}`);
      const t = await read(device, total);
      if (t[1] !== ref.total) problems.push(`n=${n}: total ${t[1]} != ${ref.total}`);
      for (const b of [input, output, count.buffer, total]) b.destroy();
    }
    expect(problems).toEqual([]);
    scan.destroy();
  });
});
