// A triangle soup as a binary little-endian PLY file (what the CLI's --ply
// writes): 3 float vertices per triangle, faces (i, i + 1, i + 2).

export function soupToPly(positions: Float32Array, comment = 'isosurface, voxel index space'): Uint8Array {
  const vertices = Math.floor(positions.length / 3);
  const triangles = Math.floor(vertices / 3);
  const header =
    'ply\nformat binary_little_endian 1.0\n' +
    `comment ${comment.replace(/\n/g, ' ')}\n` +
    `element vertex ${vertices}\nproperty float x\nproperty float y\nproperty float z\n` +
    `element face ${triangles}\nproperty list uchar int vertex_indices\nend_header\n`;
  const head = new TextEncoder().encode(header);
  const out = new Uint8Array(head.length + vertices * 12 + triangles * 13);
  out.set(head, 0);
  const view = new DataView(out.buffer);
  let at = head.length;
  for (let i = 0; i < vertices * 3; i++, at += 4) view.setFloat32(at, positions[i], true);
  for (let t = 0; t < triangles; t++) {
    view.setUint8(at, 3);
    view.setInt32(at + 1, 3 * t, true);
    view.setInt32(at + 5, 3 * t + 1, true);
    view.setInt32(at + 9, 3 * t + 2, true);
    at += 13;
  }
  return out;
}
