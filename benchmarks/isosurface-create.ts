// `node benchmarks/run.mjs benchmarks/isosurface-create.ts`: what creating an
// Isosurface costs, the first time on a device and again on the same device
// (a second volume, a reload): wall ms of Isosurface.create and the shader
// modules and compute pipelines it creates (device calls counted). With the
// per-device pipeline cache (src/gpu/pipeline-cache.ts) the second compiles
// nothing. ROOT=<tree> measures another checkout; FILE picks the volume
// (../shared/data/volumes), REPEATS the creations after the first.

const root = process.env.ROOT ?? new URL('..', import.meta.url).pathname;
const data = process.env.DATA ?? `${new URL('..', import.meta.url).pathname}/../shared/data/volumes`;
const { requestNodeGpu } = await import(`${root}/src/gpu/node-gpu.ts`);
const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
const { readFileSync } = await import('node:fs');

const gpu = await requestNodeGpu({ label: 'isosurface-create' });
const device: GPUDevice = gpu.device;
const file = process.env.FILE ?? 'hydrogen_atom_128x128x128_float32.rate8.zfp';
const repeats = Number(process.env.REPEATS ?? 3);
const stream = loadZfpStream(device, new Uint8Array(readFileSync(`${data}/${file}`)), file);

const calls = { modules: 0, pipelines: 0 };
const count = (name: 'createShaderModule' | 'createComputePipeline' | 'createComputePipelineAsync', key: keyof typeof calls) => {
  const original = (device[name] as (...a: unknown[]) => unknown).bind(device);
  (device as unknown as Record<string, unknown>)[name] = (...a: unknown[]) => {
    calls[key]++;
    return original(...a);
  };
};
count('createShaderModule', 'modules');
count('createComputePipeline', 'pipelines');
count('createComputePipelineAsync', 'pipelines');

const rows: { create: number; ms: number; modules: number; pipelines: number; triangles: number }[] = [];
for (let i = 0; i <= repeats; i++) {
  calls.modules = 0;
  calls.pipelines = 0;
  const t0 = performance.now();
  const iso = await Isosurface.create(gpu, stream);
  await device.queue.onSubmittedWorkDone();
  const ms = performance.now() - t0;
  const { modules, pipelines } = calls;
  const s = await iso.compute((iso.info.valueRange[0] + iso.info.valueRange[1]) / 2);
  rows.push({ create: i + 1, ms: Math.round(ms), modules, pipelines, triangles: s.triangles });
  iso.destroy();
}
console.log(`${file} (${root})`);
console.table(rows);
const later = rows
  .slice(1)
  .map((r) => r.ms)
  .sort((a, b) => a - b);
console.log(
  JSON.stringify({
    file,
    firstMs: rows[0].ms,
    laterMedianMs: later[Math.floor(later.length / 2)],
    firstPipelines: rows[0].pipelines,
    laterPipelines: rows.slice(1).map((r) => r.pipelines),
  }),
);
stream.destroy();
device.destroy();
