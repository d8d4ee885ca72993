// `node benchmarks/run.mjs benchmarks/isosurface-passes.ts`: compute passes, dispatches, copies and
// clears recorded for one surface (warm cache) of a shared volume (FILE, ISOS env).

const root = process.env.ROOT ?? new URL('..', import.meta.url).pathname;
const { requestNodeGpu } = await import(`${root}/src/gpu/node-gpu.ts`);
const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
const { readFileSync } = await import('node:fs');
const gpu = await requestNodeGpu({ label: 'passes' });
const file = process.env.FILE ?? 'bonsai_256x256x256_float32.rate4.zfp';
const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(`${root}/../shared/data/volumes/${file}`)), file);
// caches and vertex buffers large enough that no growth (a second submission) happens
const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: stream.info.blockCount, initialVertexCapacity: 2 ** 23 });
const isos = (process.env.ISOS ?? '37.37,40.37').split(',').map(Number);
await iso.compute(isos[0]);
await iso.compute(isos[0]);
const byLabel = new Map<string, number>();
let label = '';
let passes = 0,
  empty = 0,
  dispatches = 0,
  indirect = 0,
  copies = 0,
  clears = 0,
  current = 0;
const device = gpu.device;
const orig = device.createCommandEncoder.bind(device);
let patched = false;
device.createCommandEncoder = (d?: GPUCommandEncoderDescriptor) => {
  const enc = orig(d);
  if (!patched) {
    patched = true;
    const ep = Object.getPrototypeOf(enc);
    const bcp = ep.beginComputePass;
    ep.beginComputePass = function (this: GPUCommandEncoder, pd?: GPUComputePassDescriptor) {
      const pass = bcp.call(this, pd);
      passes++;
      current = 0;
      label = pd?.label ?? '?';
      const pp = Object.getPrototypeOf(pass);
      if (!pp.__patched) {
        pp.__patched = true;
        const dw = pp.dispatchWorkgroups,
          di = pp.dispatchWorkgroupsIndirect,
          end = pp.end;
        pp.dispatchWorkgroups = function (...a: unknown[]) {
          dispatches++;
          current++;
          return dw.apply(this, a);
        };
        pp.dispatchWorkgroupsIndirect = function (...a: unknown[]) {
          dispatches++;
          indirect++;
          current++;
          return di.apply(this, a);
        };
        pp.end = function () {
          if (current === 0) empty++;
          else byLabel.set(label, (byLabel.get(label) ?? 0) + current);
          return end.call(this);
        };
      }
      return pass;
    };
    const cb = ep.copyBufferToBuffer;
    ep.copyBufferToBuffer = function (...a: unknown[]) {
      copies++;
      return cb.apply(this, a);
    };
    const cl = ep.clearBuffer;
    ep.clearBuffer = function (...a: unknown[]) {
      clears++;
      return cl.apply(this, a);
    };
  }
  return enc;
};
const s = await iso.compute(isos[1]);
console.log(
  JSON.stringify(
    {
      root,
      file,
      iso: isos[1],
      computePasses: passes,
      passesWithDispatches: passes - empty,
      timestampMarkerPasses: empty,
      dispatches,
      indirectDispatches: indirect,
      copies,
      clears,
      active: s.activeBlocks,
      newBlocks: s.newBlocks,
      triangles: s.triangles,
      dispatchesByPass: Object.fromEntries(byLabel),
    },
    null,
    1,
  ),
);
iso.destroy();
gpu.device.destroy();
