// `node benchmarks/run.mjs benchmarks/cache-update.ts`: the cache-update
// stage (GPU timestamps) of the same surfaces with a small and a large cache
// (issue 17: its cost should follow the active and new blocks, not the
// capacity). Surfaces with 100-480 active blocks are picked from a sweep of
// the volume's range (FILE env, default the hydrogen atom, 32,768 blocks),
// then cycled (CYCLES, default 4; the first discarded), each cycle from an
// empty cache, with SLOTS (default 512,32768) slots each; prints the median
// and mean cache-update ms and the mean new and active blocks per surface,
// and writes benchmarks/results/cache-update.json (ROOT=other checkout runs
// that code instead, for A/B, and writes nothing).
const root = process.env.ROOT ?? new URL('..', import.meta.url).pathname;
const { requestNodeGpu } = await import(`${root}/src/gpu/node-gpu.ts`);
const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
const { readFileSync, writeFileSync } = await import('node:fs');
const gpu = await requestNodeGpu({ label: 'cache-update' });
const file = process.env.FILE ?? 'hydrogen_atom_128x128x128_float32.rate8.zfp';
const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(`${root}/../shared/data/volumes/${file}`)), file);
const probe = await Isosurface.create(gpu, stream, { initialCacheSlots: stream.info.blockCount });
const [lo, hi] = probe.info.valueRange;
const picked: number[] = [];
for (let i = 1; i < 80 && picked.length < 8; i++) {
  const t = Math.fround(lo + ((hi - lo) * i) / 80);
  const s = await probe.compute(t);
  if (s.activeBlocks >= 100 && s.activeBlocks <= 480) picked.push(t);
}
probe.destroy();
// alternate between far-apart surfaces, so every surface brings new blocks into a small cache
const order = picked.flatMap((_, i) => (i % 2 ? [picked[picked.length - 1 - (i >> 1)]] : [picked[i >> 1]]));
const cycles = Number(process.env.CYCLES ?? 4);
const rows: {
  slots: number;
  cacheUpdateMs: number;
  cacheUpdateMedianMs: number;
  newBlocks: number;
  activeBlocks: number;
  surfaces: number;
}[] = [];
for (const slots of (process.env.SLOTS ?? '512,32768').split(',').map(Number)) {
  const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: slots, initialVertexCapacity: 1 << 20 });
  let ms = 0;
  const samples: number[] = [];
  let fresh = 0;
  let active = 0;
  let n = 0;
  for (let c = 0; c < cycles; c++) {
    // Each cycle from an empty cache: both capacities decode new blocks (the large one never evicts).
    iso.resetCache();
    for (const t of order) {
      const s = await iso.compute(t);
      if (s.grew) throw new Error(`iso ${t}: the cache grew (${s.cacheSlots} slots): pick smaller surfaces`);
      if (c === 0) continue;
      const t1 = s.stages.find((st: { label: string }) => st.label === 'cache update')!.ms;
      ms += t1;
      samples.push(t1);
      fresh += s.newBlocks;
      active += s.activeBlocks;
      n++;
    }
  }
  samples.sort((a, b) => a - b);
  rows.push({
    slots,
    cacheUpdateMs: ms / n,
    cacheUpdateMedianMs: samples[(samples.length - 1) >> 1],
    newBlocks: fresh / n,
    activeBlocks: active / n,
    surfaces: n,
  });
  iso.destroy();
}
console.log(
  `${file}: ${order.length} surfaces x ${cycles - 1} cycles (first cycle discarded), timing ${gpu.device.features.has('timestamp-query') ? 'timestamp-query' : 'none'}`,
);
console.log('| slots | cache update ms (median) | (mean) | new blocks / surface | active blocks / surface |');
console.log('|---:|---:|---:|---:|---:|');
for (const r of rows)
  console.log(
    `| ${r.slots} | ${r.cacheUpdateMedianMs.toFixed(2)} | ${r.cacheUpdateMs.toFixed(2)} | ${r.newBlocks.toFixed(1)} | ${r.activeBlocks.toFixed(1)} |`,
  );
if (rows.length > 1)
  console.log(
    `ratio largest / smallest: median ${(rows[rows.length - 1].cacheUpdateMedianMs / rows[0].cacheUpdateMedianMs).toFixed(2)}x, mean ${(rows[rows.length - 1].cacheUpdateMs / rows[0].cacheUpdateMs).toFixed(2)}x`,
  );
if (!process.env.ROOT)
  writeFileSync(
    `${root}/benchmarks/results/cache-update.json`,
    JSON.stringify({ file, isovalues: order, cycles, rows, date: new Date().toISOString() }, null, 2) + '\n',
  );
stream.destroy();
gpu.device.destroy();
