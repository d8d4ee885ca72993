// A surface as a binary little-endian PLY mesh: float x, y, z in
// voxel index coordinates (voxel (i, j, k) at (i, j, k)), 3 vertex indices per
// face, so mesh tools see a connected surface. The page's PLY export and
// `cli extract --ply` write the GPU's welded mesh as it is (one vertex per
// cut grid edge, Isosurface.readMesh).

export interface IndexedMesh {
  /** xyz per unique vertex */
  positions: Float32Array;
  /** 3 indices per triangle */
  indices: Uint32Array;
}

/** The triangle soup (xyz per triangle corner) of an indexed mesh. */
export function soupOf(positions: Float32Array, indices: Uint32Array): Float32Array {
  const out = new Float32Array(3 * indices.length);
  for (let i = 0; i < indices.length; i++) out.set(positions.subarray(3 * indices[i], 3 * indices[i] + 3), 3 * i);
  return out;
}

export function encodePly(mesh: IndexedMesh, comments: string[] = []): Uint8Array {
  const vertices = mesh.positions.length / 3;
  const faces = mesh.indices.length / 3;
  const header =
    'ply\nformat binary_little_endian 1.0\n' +
    comments.map((c) => `comment ${c.replace(/[\r\n]+/g, ' ')}\n`).join('') +
    `element vertex ${vertices}\nproperty float x\nproperty float y\nproperty float z\n` +
    `element face ${faces}\nproperty list uchar int vertex_indices\nend_header\n`;
  const head = new TextEncoder().encode(header);
  const out = new Uint8Array(head.byteLength + vertices * 12 + faces * 13);
  out.set(head, 0);
  const view = new DataView(out.buffer);
  let at = head.byteLength;
  for (let i = 0; i < mesh.positions.length; i++, at += 4) view.setFloat32(at, mesh.positions[i], true);
  for (let f = 0; f < faces; f++) {
    out[at] = 3;
    view.setInt32(at + 1, mesh.indices[3 * f], true);
    view.setInt32(at + 5, mesh.indices[3 * f + 1], true);
    view.setInt32(at + 9, mesh.indices[3 * f + 2], true);
    at += 13;
  }
  return out;
}

/** Reads back what encodePly wrote (tests, and a check users can run in the console). */
export function parsePly(bytes: Uint8Array): { comments: string[]; positions: Float32Array; indices: Uint32Array } {
  const text = new TextDecoder('latin1').decode(bytes.subarray(0, Math.min(bytes.length, 4096)));
  const end = text.indexOf('end_header\n');
  if (!text.startsWith('ply\n') || end < 0) throw new Error('not a PLY file');
  const lines = text.slice(0, end).split('\n');
  const comments = lines.filter((l) => l.startsWith('comment ')).map((l) => l.slice(8));
  const nv = Number(/element vertex (\d+)/.exec(text)?.[1]);
  const nf = Number(/element face (\d+)/.exec(text)?.[1]);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let at = end + 'end_header\n'.length;
  const positions = new Float32Array(nv * 3);
  for (let i = 0; i < nv * 3; i++, at += 4) positions[i] = view.getFloat32(at, true);
  const indices = new Uint32Array(nf * 3);
  for (let f = 0; f < nf; f++) {
    if (bytes[at] !== 3) throw new Error(`face ${f} has ${bytes[at]} vertices`);
    for (let k = 0; k < 3; k++) indices[3 * f + k] = view.getInt32(at + 1 + 4 * k, true);
    at += 13;
  }
  return { comments, positions, indices };
}
