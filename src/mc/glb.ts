// Surfaces as one binary glTF (.glb): each surface its own mesh and node,
// its colour and opacity a material (blended where opacity < 1, drawn from
// both sides as the page draws it), positions in physical units with smooth
// normals (area-weighted over the welded vertices), so three.js and Blender
// show what the page shows. The container is written by glTF-Transform.
import { Document, WebIO } from '@gltf-transform/core';

/** Colours of surfaces 1, 2, 3...: the page's bone white first, then hues apart (sRGB). */
export const SURFACE_PALETTE: readonly (readonly [number, number, number])[] = [
  [0.86, 0.8, 0.7],
  [0.85, 0.33, 0.27],
  [0.3, 0.58, 0.86],
  [0.45, 0.74, 0.36],
  [0.9, 0.66, 0.2],
  [0.62, 0.42, 0.8],
  [0.3, 0.76, 0.74],
  [0.88, 0.47, 0.68],
];

export interface GlbSurface {
  name: string;
  /** xyz per vertex, physical units. */
  positions: Float32Array;
  indices: Uint32Array;
  /** sRGB colour, 0..1. */
  color: readonly [number, number, number];
  opacity: number;
  /** Kept on the node (`extras`): isovalue, area, enclosed volume... */
  extras?: Record<string, unknown>;
}

export async function encodeGlb(
  surfaces: GlbSurface[],
  about: { generator: string; extras?: Record<string, unknown> },
): Promise<Uint8Array> {
  const doc = new Document();
  doc.getRoot().getAsset().generator = about.generator;
  if (about.extras) doc.getRoot().getAsset().extras = about.extras;
  const buffer = doc.createBuffer();
  const scene = doc.createScene('surfaces');
  for (const s of surfaces) {
    if (s.indices.length === 0) continue; // glTF has no empty accessors: an empty surface is left out
    if (s.indices.length % 3 !== 0) throw new Error(`${s.name}: ${s.indices.length} indices is not whole triangles`);
    const material = doc
      .createMaterial(`${s.name} material`)
      .setBaseColorFactor([...s.color.map(srgbToLinear), clamp01(s.opacity)] as [number, number, number, number])
      .setAlphaMode(s.opacity < 1 ? 'BLEND' : 'OPAQUE')
      .setDoubleSided(true)
      .setMetallicFactor(0)
      .setRoughnessFactor(0.6);
    const primitive = doc
      .createPrimitive()
      .setMaterial(material)
      .setAttribute('POSITION', doc.createAccessor(`${s.name} positions`, buffer).setType('VEC3').setArray(s.positions))
      .setAttribute(
        'NORMAL',
        doc.createAccessor(`${s.name} normals`, buffer).setType('VEC3').setArray(vertexNormals(s.positions, s.indices)),
      )
      .setIndices(doc.createAccessor(`${s.name} indices`, buffer).setType('SCALAR').setArray(s.indices));
    const mesh = doc.createMesh(s.name).addPrimitive(primitive);
    const node = doc.createNode(s.name).setMesh(mesh);
    if (s.extras) node.setExtras(s.extras);
    scene.addChild(node);
  }
  doc.getRoot().setDefaultScene(scene);
  return new WebIO().writeBinary(doc);
}

/** Unit normals per vertex: the sum of its triangles' (area-weighted) normals; (0, 0, 1) where they cancel. */
export function vertexNormals(positions: Float32Array, indices: Uint32Array): Float32Array {
  const sum = new Float64Array(positions.length);
  for (let t = 0; t < indices.length; t += 3) {
    const a = 3 * indices[t],
      b = 3 * indices[t + 1],
      c = 3 * indices[t + 2];
    const ux = positions[b] - positions[a],
      uy = positions[b + 1] - positions[a + 1],
      uz = positions[b + 2] - positions[a + 2];
    const vx = positions[c] - positions[a],
      vy = positions[c + 1] - positions[a + 1],
      vz = positions[c + 2] - positions[a + 2];
    const nx = uy * vz - uz * vy,
      ny = uz * vx - ux * vz,
      nz = ux * vy - uy * vx;
    for (const p of [a, b, c]) {
      sum[p] += nx;
      sum[p + 1] += ny;
      sum[p + 2] += nz;
    }
  }
  const out = new Float32Array(positions.length);
  for (let p = 0; p < out.length; p += 3) {
    const len = Math.hypot(sum[p], sum[p + 1], sum[p + 2]);
    if (len > 0) {
      out[p] = sum[p] / len;
      out[p + 1] = sum[p + 1] / len;
      out[p + 2] = sum[p + 2] / len;
    } else out[p + 2] = 1;
  }
  return out;
}

function srgbToLinear(c: number): number {
  const x = clamp01(c);
  return x <= 0.04045 ? x / 12.92 : ((x + 0.055) / 1.055) ** 2.4;
}

function clamp01(x: number): number {
  return Math.min(1, Math.max(0, x));
}
