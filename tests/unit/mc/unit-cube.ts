// The surface of the unit cube [0, 1]^3 as an indexed mesh (12 triangles wound
// counter-clockwise seen from outside: area 6, volume 1), for the mesh
// measurement and clipping tests; `faces` leaves some out (a hole).
export const CUBE_FACES = [
  [0, 3, 2, 1],
  [4, 5, 6, 7],
  [0, 1, 5, 4],
  [2, 3, 7, 6],
  [1, 2, 6, 5],
  [0, 4, 7, 3],
];

export function unitCube(faces = CUBE_FACES): { positions: Float32Array; indices: Uint32Array } {
  const corners = [0, 1, 2, 3, 4, 5, 6, 7].map((k) => [
    k === 1 || k === 2 || k === 5 || k === 6 ? 1 : 0,
    k === 2 || k === 3 || k === 6 || k === 7 ? 1 : 0,
    k >= 4 ? 1 : 0,
  ]);
  return {
    positions: new Float32Array(corners.flat()),
    indices: new Uint32Array(faces.flatMap(([a, b, c, d]) => [a, b, c, a, c, d])),
  };
}
