// The WGSL decoder against zfp 1.0.1's own output: every vector decodes bit
// for bit (whole volume, with one shard and with many small ones), per-block
// ranges equal those of zfp's decoded volume, a GPU block list decodes into
// cache slots from a GPU count (indirect dispatch, 2D grids), and random bit
// streams decode exactly as zfpy decodes them (every exponent, subnormal and
// overflowing results included).
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { BitReader, blockRanges, decodeBlock, toWords } from '../../../src/zfp/cpu/codec.ts';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { openZfpStream } from '../../../src/zfp/format.ts';
import { IndirectArgs } from '../../../src/primitives/indirect.ts';
import { loadZfpStream, ZfpGpuStream } from '../../../src/zfp/gpu-stream.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython } from '../../helpers/python.ts';
import { firstDifference, readVector, rng, vectors } from './vectors.ts';

// Both kernel families of the block-list decode, whatever the adapter ('auto' picks one).
const DECODER_PATHS = ['emulator', 'gpu'] as const;

describe('ZfpDecoder', () => {
  gpuTest('decodes every vector bit for bit, in one shard and in many, on both paths; block ranges match', async ({ gpu }) => {
    const { device } = gpu;
    const decoders = await Promise.all(DECODER_PATHS.map((path) => ZfpDecoder.create(device, { path })));
    const decoder = decoders[0];
    for (const v of vectors) {
      const reference = readVector(v.decoded);
      const ranges = blockRanges(new Float32Array(reference.buffer), v.dims_xyz);
      for (const file of [v.compressed, v.with_header.file]) {
        // many shards: about 4 KiB each, cut inside words and blocks of the file
        for (const maxShardBytes of [undefined, 4100]) {
          const stream = loadZfpStream(device, readVector(file), file, { maxShardBytes });
          const what = `${file} with ${stream.shards.length} shard(s)`;
          if (maxShardBytes) expect(stream.shards.length).toBeGreaterThan(10);
          // small slabs for the many-shard case: 2 block rows per slab
          const slab = maxShardBytes ? v.dims_xyz[0] * v.dims_xyz[1] * 4 * 4 * 2 : undefined;
          for (const d of decoders) {
            const volume = (await d.readVolume(stream, { maxSlabBytes: slab }))!;
            expect(firstDifference(new Uint8Array(volume.buffer), reference), `${what}, ${d.path} path`).toBe('identical');
          }
          const rangeBuffer = decoder.computeBlockRanges(stream);
          const got = await readF32(device, rangeBuffer);
          expect(firstDifference(new Uint8Array(got.buffer), new Uint8Array(ranges.buffer)), `ranges of ${what}`).toBe('identical');
          rangeBuffer.destroy();
          stream.destroy();
        }
      }
    }
    for (const d of decoders) d.destroy();
  });

  for (const path of DECODER_PATHS) {
    gpuTest(`decodes a GPU list of blocks into slots, dispatched from a GPU count (${path} path)`, async ({ gpu }) => {
      const { device } = gpu;
      // a 2D grid from 3 workgroups on: exercises the indirect 2D layout with small lists
      const decoder = await ZfpDecoder.create(device, { maxWorkgroupsPerDimension: 3, path });
      expect(decoder.path).toBe(path);
      const random = rng(11);
      for (const file of ['neghip_slc_66x66x66_float32.rate4.hdr.zfp', 'ironProt_68x68x68_float32.rate2.zfp']) {
        const bytes = readVector(file);
        const info = openZfpStream(bytes, file);
        const stream = loadZfpStream(device, bytes, file, { maxShardBytes: 20000 });
        expect(stream.shards.length).toBeGreaterThan(3);
        const entries = 700;
        const slotCount = 800;
        const blockIds = Uint32Array.from({ length: entries }, () => Math.floor(random() * info.blockCount));
        // the last blocks (partial ones in neghip) are always in the list
        blockIds[0] = info.blockCount - 1;
        blockIds[1] = info.blockCount - 2;
        const slotIds = Uint32Array.from({ length: slotCount }, (_, i) => i);
        for (let i = slotCount - 1; i > 0; i--) {
          const j = Math.floor(random() * (i + 1));
          [slotIds[i], slotIds[j]] = [slotIds[j], slotIds[i]];
        }
        const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST;
        const ids = device.createBuffer({ size: entries * 4, usage });
        const slotsOf = device.createBuffer({ size: slotCount * 4, usage });
        device.queue.writeBuffer(ids, 0, blockIds);
        device.queue.writeBuffer(slotsOf, 0, slotIds);
        const slots = device.createBuffer({ size: slotCount * 256, usage: usage | GPUBufferUsage.COPY_SRC });
        device.queue.writeBuffer(slots, 0, new Uint32Array(slotCount * 64).fill(0xdeadbeef));
        // counts at unaligned offsets; the first list decodes entries [0, first), the second [448, entries)
        const first = 450;
        const counts = device.createBuffer({ size: 1024, usage });
        device.queue.writeBuffer(counts, 260, new Uint32Array([first]));
        device.queue.writeBuffer(counts, 516, new Uint32Array([entries - 448]));
        const encoder = device.createCommandEncoder();
        decoder.encodeDecodeBlocks(encoder, { stream, blockIds: ids, slotIds: slotsOf, count: { buffer: counts, offset: 260 }, slots });
        const pass = encoder.beginComputePass();
        decoder.encodeDecodeBlocks(pass, {
          stream,
          blockIds: { buffer: ids, offset: 1792 }, // entries 448.. : overlaps the first list by 2 entries
          slotIds: { buffer: slotsOf, offset: 1792 },
          count: { buffer: counts, offset: 516 },
          slots,
        });
        pass.end();
        device.queue.submit([encoder.finish()]);
        const got = await readU32(device, slots);

        const words = toWords(bytes);
        const expected = new Uint32Array(slotCount * 64).fill(0xdeadbeef);
        const block = new Uint32Array(64);
        const decodeTo = (entry: number) => {
          decodeBlock(new BitReader(words, info.payloadBitOffset + blockIds[entry] * info.bitsPerBlock), info.bitsPerBlock, block);
          expected.set(block, slotIds[entry] * 64);
        };
        for (let i = 0; i < first; i++) decodeTo(i);
        for (let i = 448; i < entries; i++) decodeTo(i);
        expect(firstDifference(new Uint8Array(got.buffer), new Uint8Array(expected.buffer)), file).toBe('identical');
        for (const b of [ids, slotsOf, slots, counts]) b.destroy();
        stream.destroy();
      }
      decoder.destroy();
    });

    gpuTest(`decodes block lists of awkward lengths into slots like the CPU decoder (${path} path)`, async ({ gpu }) => {
      const { device } = gpu;
      const decoder = await ZfpDecoder.create(device, { path });
      const random = rng(23);
      const file = 'neghip_slc_66x66x66_float32.rate4.hdr.zfp'; // partial blocks at the far faces
      const bytes = readVector(file);
      const info = openZfpStream(bytes, file);
      const words = toWords(bytes);
      const stream = loadZfpStream(device, bytes, file, { maxShardBytes: 6000 }); // entries in other shards are skipped per shard
      const lengths = [0, 1, 31, 32, 33, 63, 64, 65, 100, 129, info.blockCount + 7];
      const capacity = Math.max(...lengths);
      const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST;
      const ids = device.createBuffer({ size: capacity * 4, usage });
      const slotsOf = device.createBuffer({ size: capacity * 4, usage });
      const count = device.createBuffer({ size: 4, usage });
      const slots = device.createBuffer({ size: (capacity + 5) * 256, usage: usage | GPUBufferUsage.COPY_SRC });
      const block = new Uint32Array(64);
      for (const n of lengths) {
        // blocks in any order, repeats allowed; slots a random permutation (some slots stay untouched)
        const blockIds = Uint32Array.from({ length: capacity }, () => Math.floor(random() * info.blockCount));
        const slotIds = Uint32Array.from({ length: capacity + 5 }, (_, i) => i);
        for (let i = slotIds.length - 1; i > 0; i--) {
          const j = Math.floor(random() * (i + 1));
          [slotIds[i], slotIds[j]] = [slotIds[j], slotIds[i]];
        }
        device.queue.writeBuffer(ids, 0, blockIds);
        device.queue.writeBuffer(slotsOf, 0, slotIds, 0, capacity);
        device.queue.writeBuffer(count, 0, new Uint32Array([n]));
        device.queue.writeBuffer(slots, 0, new Uint32Array((capacity + 5) * 64).fill(0xdeadbeef));
        const encoder = device.createCommandEncoder();
        decoder.encodeDecodeBlocks(encoder, { stream, blockIds: ids, slotIds: slotsOf, count: { buffer: count, offset: 0 }, slots });
        device.queue.submit([encoder.finish()]);
        const got = await readU32(device, slots);
        const expected = new Uint32Array((capacity + 5) * 64).fill(0xdeadbeef);
        for (let i = 0; i < n; i++) {
          decodeBlock(new BitReader(words, info.payloadBitOffset + blockIds[i] * info.bitsPerBlock), info.bitsPerBlock, block);
          expected.set(block, slotIds[i] * 64);
        }
        expect(firstDifference(new Uint8Array(got.buffer), new Uint8Array(expected.buffer)), `${n} entries`).toBe('identical');
      }
      for (const b of [ids, slotsOf, slots, count]) b.destroy();
      stream.destroy();
      decoder.destroy();
    });
  }

  gpuTest('turns GPU counts into dispatch grids that cover them', async ({ gpu }) => {
    const { device } = gpu;
    const args = await IndirectArgs.create(device, { itemsPerWorkgroup: 64 });
    const counts = [0, 1, 64, 65, 65535 * 64, 65535 * 64 + 1, 3 * 65535 * 64 + 5, 0xffffffc0];
    const countBuffer = device.createBuffer({ size: counts.length * 4, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(countBuffer, 0, new Uint32Array(counts));
    const out = device.createBuffer({ size: counts.length * 16, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC });
    for (let i = 0; i < counts.length; i++) {
      const encoder = device.createCommandEncoder();
      const pass = encoder.beginComputePass();
      args.encode(pass, { count: { buffer: countBuffer, offset: 4 * i } });
      pass.end();
      encoder.copyBufferToBuffer(args.buffer, 0, out, 16 * i, 16);
      device.queue.submit([encoder.finish()]);
    }
    const got = await readU32(device, out);
    counts.forEach((count, i) => {
      const [x, y, z, c] = got.subarray(4 * i, 4 * i + 4);
      expect(c).toBe(count);
      expect(z).toBe(1);
      expect(x).toBeLessThanOrEqual(65535);
      const groups = Math.ceil(count / 64);
      expect(x * y).toBeGreaterThanOrEqual(groups);
      expect(x * y - groups).toBeLessThan(Math.max(1, y)); // less than one row of overshoot
    });
    args.destroy();
    countBuffer.destroy();
    out.destroy();
  });

  gpuTest('decodes random bit streams exactly as zfpy does (all exponents)', async ({ gpu }) => {
    const { device } = gpu;
    const decoder = await ZfpDecoder.create(device);
    const dir = mkdtempSync(join(tmpdir(), 'zfp-fuzz-'));
    const random = rng(99);
    const cases = [
      { dims: [33, 33, 17], rate: 5.5 },
      { dims: [32, 32, 32], rate: 1 },
      { dims: [37, 30, 29], rate: 16.25 },
      { dims: [36, 32, 36], rate: 32 },
    ] as const;
    const files: string[] = [];
    const ours: Uint8Array[] = [];
    for (const [i, c] of cases.entries()) {
      const name = `fuzz${i}_${c.dims.join('x')}_float32.raw.crate${c.rate}.zfp`;
      const grid = c.dims.map((n) => Math.ceil(n / 4));
      const bits = Math.floor(64 * c.rate + 0.5);
      const size = Math.ceil((grid[0] * grid[1] * grid[2] * bits) / 64) * 8;
      const bytes = new Uint8Array(size);
      for (let j = 0; j < size; j++) bytes[j] = Math.floor(random() * 256);
      // blocks flagged non-zero (but every 16th), with every exponent: e = b mod 256
      for (let b = 0; b < grid[0] * grid[1] * grid[2]; b++) {
        const field = ((b & 255) << 1) | (b % 16 === 7 ? 0 : 1);
        for (let k = 0; k < 9; k++) {
          const bit = b * bits + k;
          bytes[bit >> 3] = (bytes[bit >> 3] & ~(1 << (bit & 7))) | (((field >> k) & 1) << (bit & 7));
        }
      }
      writeFileSync(join(dir, name), bytes);
      files.push(name);
      const stream = loadZfpStream(device, bytes, name);
      ours.push(new Uint8Array((await decoder.readVolume(stream))!.buffer));
      stream.destroy();
    }
    runPython(
      `
import sys, json, numpy as np, zfpy
d, cases = sys.argv[1], json.loads(sys.argv[2])
for i, (name, c) in enumerate(cases):
    x, y, z = c['dims']
    a = zfpy._decompress(open(d + '/' + name, 'rb').read(), zfpy.type_float, [z, y, x], rate=c['rate'])
    np.ascontiguousarray(a, dtype=np.float32).tofile(d + '/' + name + '.zfpy.raw')
`,
      [dir, JSON.stringify(files.map((f, i) => [f, cases[i]]))],
    );
    let infinities = 0;
    let subnormals = 0;
    files.forEach((f, i) => {
      const ref = new Uint8Array(readFileSync(join(dir, `${f}.zfpy.raw`)));
      expect(firstDifference(ours[i], ref), f).toBe('identical');
      const bits = new Uint32Array(ref.buffer);
      for (const w of bits) {
        if ((w & 0x7f800000) === 0x7f800000) infinities++;
        if ((w & 0x7f800000) === 0 && (w & 0x7fffff) !== 0) subnormals++;
      }
    });
    expect(infinities, 'infinities in the fuzzed output').toBeGreaterThan(0);
    expect(subnormals, 'subnormals in the fuzzed output').toBeGreaterThan(0);
    decoder.destroy();
  });
});

describe('ZfpGpuStream', () => {
  gpuTest('rejects malformed files before allocating anything on the GPU', async ({ gpu }) => {
    const { device } = gpu;
    let live = 0;
    const create = device.createBuffer.bind(device);
    device.createBuffer = (desc: GPUBufferDescriptor) => {
      const buffer = create(desc);
      live++;
      const destroy = buffer.destroy.bind(buffer);
      buffer.destroy = () => {
        live--;
        destroy();
      };
      return buffer;
    };
    const good = readVector(vectors[4].with_header.file);
    const bad: [string, Uint8Array][] = [
      ['wrong_magic.zfp', Uint8Array.from(good, (b, i) => (i === 0 ? 0x79 : b))],
      ['truncated.zfp', good.subarray(0, good.byteLength - 100)],
      ['precision.zfp', Uint8Array.from(good, (b, i) => (i === 11 ? 0x80 : b))], // mode 2048 + ... : fixed precision
      ['noshape_float32.raw.crate4.zfp', readVector(vectors[1].compressed)],
    ];
    for (const [name, bytes] of bad) {
      expect(() => loadZfpStream(device, bytes, name), name).toThrow(name);
      expect(live, `${name}: live GPU buffers`).toBe(0);
    }
    const stream = loadZfpStream(device, good, 'good.zfp');
    expect(live).toBeGreaterThan(0);
    stream.destroy();
    expect(live).toBe(0);
    expect(stream).toBeInstanceOf(ZfpGpuStream);
  });
});
