// `node benchmarks/run.mjs benchmarks/isosurface-stages.ts`: warm-cache mean GPU ms per stage of a
// few bonsai surfaces (FILE, ISOS, REPEATS env): a quick A/B probe between builds.
const root = process.env.ROOT ?? new URL('..', import.meta.url).pathname;
const { requestNodeGpu } = await import(`${root}/src/gpu/node-gpu.ts`);
const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
const { readFileSync } = await import('node:fs');
const gpu = await requestNodeGpu({ label: 'stages' });
const file = process.env.FILE ?? 'bonsai_256x256x256_float32.rate4.zfp';
const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(`${root}/../shared/data/volumes/${file}`)), file);
const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: stream.info.blockCount >> 2 });
const isos = (process.env.ISOS ?? '37.37,60.37,90.37').split(',').map(Number);
for (const t of isos) await iso.compute(t);
const sums: Record<string, number> = {};
let n = 0;
for (let r = 0; r < Number(process.env.REPEATS ?? 2); r++) {
  for (const t of isos) {
    const s = await iso.compute(t);
    for (const st of s.stages) sums[st.label] = (sums[st.label] ?? 0) + st.ms;
    sums.total = (sums.total ?? 0) + s.gpuMs;
    n++;
  }
}
console.log(root, Object.entries(sums).map(([k, v]) => `${k} ${(v / n).toFixed(1)}`).join(' | '));
iso.destroy();
gpu.device.destroy();
