// Area and enclosed volume of an indexed triangle mesh in physical units.
//
// The mesh may come in pieces whose shared vertices are duplicated (a store's
// chunks and levels, each welded on its own), so vertices are first welded
// by exact position. The enclosed volume is the divergence theorem's sum of
// signed tetrahedra (origin, a, b, c); it means something only where the
// surface is closed, so it is null otherwise. Closed here is exactly what
// that sum needs: every directed edge a->b is matched by an edge b->a (the
// triangles' boundary is empty), which pinch points and zero-area triangles
// at grid points do not break, while a hole, a surface cut by the volume's
// box or two pieces that disagree on their seam do.

export interface SurfaceMeasure {
  triangles: number;
  /** Sum of triangle areas, physical units squared (float64 from the float32 positions). */
  area: number;
  /** |sum of signed tetrahedra|, physical units cubed; null when the surface is open. */
  enclosedVolume: number | null;
  closed: boolean;
  /** Edges (after welding by position) used more often in one direction than in the other: where the surface is open. */
  openEdges: number;
}

/** voxel (i, j, k) at ((i, j, k) + origin) * voxelSize */
export interface Placement {
  voxelSize: readonly [number, number, number];
  origin?: readonly [number, number, number];
}

export function measureSurface(positions: Float32Array, indices: Uint32Array, placement?: Placement): SurfaceMeasure {
  if (indices.length % 3 !== 0) throw new Error(`measureSurface: ${indices.length} indices is not whole triangles`);
  const vertexCount = Math.floor(positions.length / 3);
  for (let i = 0; i < indices.length; i++) {
    if (indices[i] >= vertexCount) throw new Error(`measureSurface: index ${indices[i]} past ${vertexCount} vertices`);
  }
  const [sx, sy, sz] = placement?.voxelSize ?? [1, 1, 1];
  const [ox, oy, oz] = placement?.origin ?? [0, 0, 0];
  // tetrahedra from a point on the surface, not the origin: far from the origin, the terms would cancel in float64
  const rx = indices.length > 0 ? (positions[3 * indices[0]] + ox) * sx : 0,
    ry = indices.length > 0 ? (positions[3 * indices[0] + 1] + oy) * sy : 0,
    rz = indices.length > 0 ? (positions[3 * indices[0] + 2] + oz) * sz : 0;
  let area = 0;
  let signedVolume = 0;
  for (let t = 0; t < indices.length; t += 3) {
    const a = 3 * indices[t],
      b = 3 * indices[t + 1],
      c = 3 * indices[t + 2];
    const ax = (positions[a] + ox) * sx,
      ay = (positions[a + 1] + oy) * sy,
      az = (positions[a + 2] + oz) * sz;
    const bx = (positions[b] + ox) * sx,
      by = (positions[b + 1] + oy) * sy,
      bz = (positions[b + 2] + oz) * sz;
    const cx = (positions[c] + ox) * sx,
      cy = (positions[c + 1] + oy) * sy,
      cz = (positions[c + 2] + oz) * sz;
    // area from the edge vectors (not the corners' cross products): no cancellation far from the origin
    const ux = bx - ax,
      uy = by - ay,
      uz = bz - az;
    const vx = cx - ax,
      vy = cy - ay,
      vz = cz - az;
    const nx = uy * vz - uz * vy,
      ny = uz * vx - ux * vz,
      nz = ux * vy - uy * vx;
    area += 0.5 * Math.sqrt(nx * nx + ny * ny + nz * nz);
    // tetrahedron (r, a, b, c) = (a - r) . (u x v) / 6
    signedVolume += ((ax - rx) * nx + (ay - ry) * ny + (az - rz) * nz) / 6;
  }
  const openEdges = countOpenEdges(weldByPosition(positions), indices);
  const closed = openEdges === 0 && indices.length > 0;
  return {
    triangles: indices.length / 3,
    area,
    enclosedVolume: closed ? Math.abs(signedVolume) : null,
    closed,
    openEdges,
  };
}

/** Per vertex, the first vertex at exactly the same position (bit for bit; -0 and 0 differ, which MC never makes at one point). */
export function weldByPosition(positions: Float32Array): Uint32Array {
  const n = Math.floor(positions.length / 3);
  const bits = new Uint32Array(positions.buffer, positions.byteOffset, 3 * n);
  const size = tableSize(n);
  const mask = size - 1;
  const slots = new Int32Array(size).fill(-1);
  const welded = new Uint32Array(n);
  for (let v = 0; v < n; v++) {
    const x = bits[3 * v],
      y = bits[3 * v + 1],
      z = bits[3 * v + 2];
    let h = hash3(x, y, z) & mask;
    for (;;) {
      const s = slots[h];
      if (s < 0) {
        slots[h] = v;
        welded[v] = v;
        break;
      }
      if (bits[3 * s] === x && bits[3 * s + 1] === y && bits[3 * s + 2] === z) {
        welded[v] = s;
        break;
      }
      h = (h + 1) & mask;
    }
  }
  return welded;
}

/** Undirected edges whose two directions are not used equally often. */
function countOpenEdges(welded: Uint32Array, indices: Uint32Array): number {
  const edges = indices.length;
  const size = tableSize(edges);
  const mask = size - 1;
  // key: (lower vertex, higher vertex); value: uses lower->higher minus uses higher->lower
  const lo = new Uint32Array(size);
  const hi = new Int32Array(size).fill(-1);
  const balance = new Int32Array(size);
  for (let t = 0; t < indices.length; t += 3) {
    for (let e = 0; e < 3; e++) {
      const a = welded[indices[t + e]];
      const b = welded[indices[t + ((e + 1) % 3)]];
      if (a === b) continue; // a corner repeated: no edge
      const l = Math.min(a, b);
      const u = Math.max(a, b);
      let h = hash3(l, u, 0x9e3779b9) & mask;
      for (;;) {
        if (hi[h] < 0) {
          lo[h] = l;
          hi[h] = u;
          break;
        }
        if (lo[h] === l && hi[h] === u) break;
        h = (h + 1) & mask;
      }
      balance[h] += a < b ? 1 : -1;
    }
  }
  let open = 0;
  for (let h = 0; h < size; h++) if (hi[h] >= 0 && balance[h] !== 0) open++;
  return open;
}

/** A power of two at least twice `n` (open addressing at most half full). */
function tableSize(n: number): number {
  let size = 16;
  while (size < 2 * n) size *= 2;
  return size;
}

function hash3(x: number, y: number, z: number): number {
  let h = Math.imul(x ^ 0x2545f491, 0x9e3779b1);
  h = Math.imul(h ^ (h >>> 15) ^ y, 0x85ebca77);
  h = Math.imul(h ^ (h >>> 13) ^ z, 0xc2b2ae3d);
  return (h ^ (h >>> 16)) >>> 0;
}
