import { cameraForBox, cameraFromView, sceneRadiusOf, viewCut, type CutLevel } from '/work/main/src/store/view/cut.ts';
import { DEFAULT_VIEWPORT } from '/work/main/src/store/view/view-request.ts';
type V3 = [number, number, number];
const levels: CutLevel[] = Array.from({ length: 6 }, (_, L) => { const d = Math.ceil(2048 / 2 ** L); const g = Math.ceil(d / 64); return { dims: [d, d, d] as V3, chunkEdge: 64, chunkGrid: [g, g, g] as V3 }; });
const COST = 64 ** 3 + (48 * 4096 + 32) + 4096 * 0.5 * 384;
const box: [number, number, number, number, number, number] = process.argv[2] === 'mid' ? [896, 896, 1792, 1151, 1151, 2047] : [1792, 1792, 1792, 2047, 2047, 2047];
const framed = cameraForBox(box, [1, 1, 1], DEFAULT_VIEWPORT);
const camera = cameraFromView(framed.state, DEFAULT_VIEWPORT, sceneRadiusOf(box, [1, 1, 1]));
const inp = { levels, voxelSize: [1, 1, 1] as V3, camera, tolerancePx: 1.5, finest: 0, coarsest: 5, needs: () => () => true, chunkBytes: () => COST };
const inBox = (n: { level: number; coords: V3 }) => { const e = 64 * 2 ** n.level; return n.coords.every((c, a) => c * e >= box[a] && (c + 1) * e <= box[a + 3] + 1); };
for (const b of [Infinity, (256 << 20) * 0.8, (512 << 20) * 0.8, (1024 << 20) * 0.8]) {
  const cut = viewCut({ ...inp, budgetBytes: b });
  const by: Record<number, number> = {}; const byBox: Record<number, number> = {};
  for (const n of cut.nodes) { by[n.level] = (by[n.level] ?? 0) + 1; if (inBox(n)) byBox[n.level] = (byBox[n.level] ?? 0) + 1; }
  const wanted = cut.levels.map((l) => l.wanted.length);
  console.log(`budget ${(b / 2 ** 20).toFixed(0)} MB: bytes ${(cut.bytes / 2 ** 20).toFixed(0)} MB, chunks/ MB ${(COST / 2 ** 20).toFixed(2)}, leaves by level ${JSON.stringify(by)}, in box ${JSON.stringify(byBox)}, wanted ${wanted}`);
}
