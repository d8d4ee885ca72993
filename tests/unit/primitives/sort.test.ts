import { describe, expect } from 'vitest';
import { RadixSortByKey } from '../../../src/primitives/sort.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { cpuSortPermutation, diff, gpuCount, randomU32, read, upload } from './helpers.ts';

describe('RadixSortByKey', () => {
  gpuTest('small', async ({ gpu }) => {
    const { device } = gpu;
    const sort = await RadixSortByKey.create(device, { capacity: 70000 });
    const problems: string[] = [];
    for (const n of [0, 1, 2, 63, 64, 65, 255, 256, 257, 4095, 65535]) {
      for (const descending of [false, true]) {
        const extra = 5;
        const keys = randomU32(n + extra, n + 7);
        const values = randomU32(n + extra, n + 9);
        const k = upload(device, 'keys', keys);
        const v = upload(device, 'values', values);
        const ko = upload(device, 'keysOut', new Uint32Array(0), n + extra);
        const vo = upload(device, 'valuesOut', new Uint32Array(0), n + extra);
        const count = gpuCount(device, n);
        const enc = device.createCommandEncoder();
        sort.encode(enc, { keys: k, values: v, keysOut: ko, valuesOut: vo, count, descending });
        device.queue.submit([enc.finish()]);
        const perm = cpuSortPermutation(keys, n, descending);
        const ek = new Uint32Array(n);
        const ev = new Uint32Array(n);
        for (let i = 0; i < n; i++) {
          ek[i] = keys[perm[i]];
          ev[i] = values[perm[i]];
        }
        const dk = diff(await read(device, ko), ek, 'key');
        const dv = diff(await read(device, vo), ev, 'value');
        if (dk || dv) problems.push(`n=${n} desc=${descending}: ${dk} ${dv}`);
      }
    }
    expect(problems).toEqual([]);
    sort.destroy();
  });
});
