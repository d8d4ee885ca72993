// `node benchmarks/run.mjs benchmarks/isosurface-stages.ts [ROOT ...]`: mean GPU ms per stage of a
// few bonsai surfaces (FILE, ISOS, REPEATS env), warm cache, and the triangles of each isovalue.
// A quick A/B probe between builds: with several checkouts as arguments, each surface is computed
// by every checkout in turn in one process on one device, so they share the machine's load (the
// only fair comparison on a busy machine with SwiftShader). Without arguments: this checkout.
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

const here = fileURLToPath(new URL('..', import.meta.url));
const roots = process.argv.slice(2).length > 0 ? process.argv.slice(2) : [process.env.ROOT ?? here];
const { requestNodeGpu } = await import(`${roots[0]}/src/gpu/node-gpu.ts`);
const gpu = await requestNodeGpu({ label: 'stages' });
const file = process.env.FILE ?? 'bonsai_256x256x256_float32.rate4.zfp';
const bytes = new Uint8Array(readFileSync(`${here}/../shared/data/volumes/${file}`));
const isos = (process.env.ISOS ?? '37.37,60.37,90.37').split(',').map(Number);
const repeats = Number(process.env.REPEATS ?? 3);

interface Run {
  root: string;
  iso: { compute(t: number): Promise<{ stages: { label: string; ms: number }[]; gpuMs: number; triangles: number }>; destroy(): void };
  samples: Map<string, number[]>;
  triangles: number[];
}
const runs: Run[] = [];
for (const root of roots) {
  const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
  const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
  const stream = loadZfpStream(gpu.device, bytes, file);
  // a cache and vertex buffers large enough that no surface grows them
  const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: stream.info.blockCount >> 1, initialVertexCapacity: 2 ** 23 });
  for (const t of isos) await iso.compute(t); // warm the cache, the first surfaces discarded
  runs.push({ root, iso, samples: new Map(), triangles: [] });
}
for (let r = 0; r < repeats; r++) {
  for (const t of isos) {
    for (const run of runs) {
      const s = await run.iso.compute(t);
      const add = (label: string, ms: number) => run.samples.set(label, [...(run.samples.get(label) ?? []), ms]);
      for (const st of s.stages) add(st.label, st.ms);
      add('total', s.gpuMs);
      if (r === 0) run.triangles.push(s.triangles);
    }
  }
}
const mean = (a: number[]) => a.reduce((x, y) => x + y, 0) / a.length;
for (const run of runs) {
  const stages = [...run.samples].map(([label, ms]) => `${label} ${mean(ms).toFixed(1)}`).join(' | ');
  console.log(`${run.root}: ${stages} | triangles ${run.triangles.join(', ')}`);
  run.iso.destroy();
}
gpu.device.destroy();
