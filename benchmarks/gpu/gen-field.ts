// The converter's generated volume (`gen:XxYxZ`, converter/zfpzarr/inputs/
// formats.py generated_block) computed here for in-core volumes made on the
// machine that runs the benchmark (nothing to carry): a sum of products of
// 1-D float32 waves of the voxel's position over the whole shape, in float32
// as numpy evaluates it.
export function generatedField(dims: readonly [number, number, number]): Float32Array {
  const [nx, ny, nz] = dims;
  const f = Math.fround;
  const wave = (n: number, freq: number, phase: number) => Float32Array.from({ length: n }, (_, i) => f(Math.sin(freq * (i / n) + phase)));
  const x1 = wave(nx, 6.3, 0.2),
    y1 = wave(ny, 4.1, 1.0),
    y2 = wave(ny, 5.3, 0.7),
    z2 = wave(nz, 3.7, 2.0),
    z3 = wave(nz, 7.9, 1.3),
    x3 = wave(nx, 2.9, 0.4),
    xh = wave(nx, 0.9 * nx, 0),
    yh = wave(ny, 0.7 * ny, 0),
    zh = wave(nz, 1.1 * nz, 0);
  const out = new Float32Array(nx * ny * nz);
  let i = 0;
  for (let z = 0; z < nz; z++) {
    for (let y = 0; y < ny; y++) {
      const yz = f(y2[y] * z2[z]);
      for (let x = 0; x < nx; x++) {
        let v = f(x1[x] * y1[y]);
        v = f(v + yz);
        v = f(v + f(z3[z] * x3[x]));
        // 0.05 * (hx * hy * hz): numpy multiplies left to right in float32
        v = f(v + f(0.05 * f(f(xh[x] * yh[y]) * zh[z])));
        out[i++] = v;
      }
    }
  }
  return out;
}
