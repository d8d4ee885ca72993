// A WebGPU view frustum as 6 planes and the conservative box test the view
// cut (cut.ts) splits by.

/** The 6 planes (a, b, c, d: a x + b y + c z + d >= 0 inside) of a WebGPU world -> clip matrix. */
export function frustumPlanes(m: ArrayLike<number>): Float64Array {
  const row = (r: number) => [m[r], m[4 + r], m[8 + r], m[12 + r]];
  const [r0, r1, r2, r3] = [row(0), row(1), row(2), row(3)];
  const out = new Float64Array(24);
  const rows = [
    r3.map((v, i) => v + r0[i]), // x >= -w
    r3.map((v, i) => v - r0[i]), // x <= w
    r3.map((v, i) => v + r1[i]), // y >= -w
    r3.map((v, i) => v - r1[i]), // y <= w
    r2, // z >= 0
    r3.map((v, i) => v - r2[i]), // z <= w
  ];
  rows.forEach((p, i) => out.set(p, 4 * i));
  return out;
}

/** False only when the box lies wholly outside one plane (conservative: some boxes outside pass). */
export function boxInFrustum(p: Float64Array, x0: number, y0: number, z0: number, x1: number, y1: number, z1: number): boolean {
  for (let i = 0; i < 24; i += 4) {
    const a = p[i];
    const b = p[i + 1];
    const c = p[i + 2];
    if (a * (a >= 0 ? x1 : x0) + b * (b >= 0 ? y1 : y0) + c * (c >= 0 ? z1 : z0) + p[i + 3] < 0) return false;
  }
  return true;
}
