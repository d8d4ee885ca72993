// `extract`'s measurements and glTF against outside truth: a sphere's
// distance field written as NRRD by pynrrd with an anisotropic voxel size,
// measured by VTK (vtkMarchingCubes over the same values and spacing, then
// vtkMassProperties; vtkFeatureEdges for whether it is closed) and against
// the analytic sphere; the same field at a radius the volume's box cuts:
// open, no volume, as VTK finds boundary edges. neghip (uint8, lossless at
// rate 20): area and volume of two closed surfaces against VTK's. The .glb
// is read back by pygltflib: one mesh per surface, vertex and index counts,
// materials, positions in physical units.
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { runPython, sharedData } from '../../helpers/python.ts';
import { cli } from '../store/stores.ts';

interface Rec {
  iso: number;
  triangles: number;
  vertices: number;
  indices: number;
  area: number;
  enclosedVolume: number | null;
  openEdges: number;
  bbox: { min: number[]; max: number[] };
  glbMesh?: string;
}

const VTK_MEASURE = `
import sys, json, numpy as np, vtk
from vtk.util import numpy_support
def measure(values_zyx, spacing, isos):
    img = vtk.vtkImageData()
    nz, ny, nx = values_zyx.shape
    img.SetDimensions(nx, ny, nz)
    img.SetSpacing(*spacing)
    img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(values_zyx.ravel().astype(np.float32), deep=True))
    out = []
    for iso in isos:
        mc = vtk.vtkMarchingCubes(); mc.SetInputData(img); mc.SetValue(0, iso); mc.Update()
        tri = vtk.vtkTriangleFilter(); tri.SetInputConnection(mc.GetOutputPort())
        mp = vtk.vtkMassProperties(); mp.SetInputConnection(tri.GetOutputPort()); mp.Update()
        fe = vtk.vtkFeatureEdges(); fe.SetInputConnection(mc.GetOutputPort())
        fe.BoundaryEdgesOn(); fe.FeatureEdgesOff(); fe.NonManifoldEdgesOff(); fe.ManifoldEdgesOff(); fe.Update()
        out.append({'iso': iso, 'triangles': mc.GetOutput().GetNumberOfCells(), 'area': mp.GetSurfaceArea(),
                    'volume': mp.GetVolume(), 'boundaryEdges': fe.GetOutput().GetNumberOfCells()})
    return out
`;

describe('extract: area, enclosed volume and glTF', () => {
  const dir = mkdtempSync(join(tmpdir(), 'measure-cli-'));

  it('a sphere with an anisotropic voxel size: VTK and the analytic sphere; cut by the box: open', () => {
    const nrrd = join(dir, 'sphere.nrrd');
    const R = 7;
    const vtkFigures = JSON.parse(
      runPython(
        `${VTK_MEASURE}
import nrrd
spacing = (0.5, 0.6, 0.8)
nx, ny, nz = 40, 36, 30
z, y, x = np.meshgrid(np.arange(nz) * spacing[2], np.arange(ny) * spacing[1], np.arange(nx) * spacing[0], indexing='ij')
c = (9.75, 10.5, 11.6)
f = np.sqrt((x - c[0])**2 + (y - c[1])**2 + (z - c[2])**2).astype(np.float32)
# pynrrd writes the first axis fastest in the file when given Fortran order: x fastest, as the page reads it
nrrd.write(sys.argv[1], np.asfortranarray(f.transpose(2, 1, 0)), {'spacings': list(spacing), 'encoding': 'raw'})
print(json.dumps(measure(f, spacing, [${R}, 11])))
`,
        [nrrd],
      ),
    );
    const out = join(dir, 'sphere.json');
    const glb = join(dir, 'sphere.glb');
    const r = cli('extract', nrrd, '--iso', `${R},11`, '--rate', '24', '--glb', glb, '--json', out);
    expect(r.status, r.stderr).toBe(0);
    const result = JSON.parse(readFileSync(out, 'utf8'));
    expect(result.voxelSize).toEqual([0.5, 0.6, 0.8]);
    const [closed, open] = result.isosurfaces as Rec[];
    const [vtkClosed, vtkOpen] = vtkFigures;
    expect(vtkClosed.boundaryEdges).toBe(0);
    expect(closed.openEdges).toBe(0);
    expect(closed.triangles).toBe(vtkClosed.triangles);
    expect(Math.abs(closed.area / vtkClosed.area - 1)).toBeLessThan(1e-3);
    expect(Math.abs(closed.enclosedVolume! / vtkClosed.volume - 1)).toBeLessThan(1e-3);
    expect(Math.abs(closed.area / (4 * Math.PI * R * R) - 1)).toBeLessThan(0.01);
    expect(Math.abs(closed.enclosedVolume! / ((4 / 3) * Math.PI * R ** 3) - 1)).toBeLessThan(0.01);
    // radius 11 from x = 9.75: the box cuts it at x = 0
    expect(vtkOpen.boundaryEdges).toBeGreaterThan(0);
    expect(open.enclosedVolume).toBeNull();
    expect(open.openEdges).toBe(vtkOpen.boundaryEdges);
    expect(Math.abs(open.area / vtkOpen.area - 1)).toBeLessThan(1e-3);

    const read = JSON.parse(
      runPython(
        `
import sys, json, numpy as np
from pygltflib import GLTF2
g = GLTF2().load_binary(sys.argv[1])
blob = g.binary_blob()
def array(accessor, dtype, width):
    # honours the view's byteStride (glTF-Transform interleaves vertex attributes)
    a = g.accessors[accessor]; v = g.bufferViews[a.bufferView]
    size = np.dtype(dtype).itemsize * width; stride = v.byteStride or size
    raw = np.frombuffer(blob, np.uint8, stride * (a.count - 1) + size, (v.byteOffset or 0) + (a.byteOffset or 0))
    rows = np.lib.stride_tricks.as_strided(raw, (a.count, size), (stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(-1, width)
out = []
for m in g.meshes:
    p = m.primitives[0]
    pos = array(p.attributes.POSITION, '<f4', 3); nrm = array(p.attributes.NORMAL, '<f4', 3); idx = array(p.indices, '<u4', 1)
    mat = g.materials[p.material]
    out.append({'name': m.name, 'vertices': len(pos), 'indices': len(idx), 'maxIndex': int(idx.max()),
                'min': pos.min(0).tolist(), 'max': pos.max(0).tolist(), 'normalLength': [float(np.linalg.norm(nrm, axis=1).min()), float(np.linalg.norm(nrm, axis=1).max())],
                'color': mat.pbrMetallicRoughness.baseColorFactor, 'alphaMode': mat.alphaMode, 'doubleSided': mat.doubleSided})
print(json.dumps({'meshes': out, 'scenes': len(g.scenes), 'nodes': [n.name for n in g.nodes]}))
`,
        [glb],
      ),
    );
    expect(read.scenes).toBe(1);
    expect(read.nodes).toEqual([closed.glbMesh, open.glbMesh]);
    read.meshes.forEach((m: Record<string, never>, i: number) => {
      const rec = [closed, open][i];
      expect(m.name).toBe(rec.glbMesh);
      expect(m.vertices).toBe(rec.vertices);
      expect(m.indices).toBe(rec.indices);
      expect(m.maxIndex).toBe(rec.vertices - 1);
      for (let a = 0; a < 3; a++) {
        expect(m.min[a]).toBeCloseTo(rec.bbox.min[a] * result.voxelSize[a], 4);
        expect(m.max[a]).toBeCloseTo(rec.bbox.max[a] * result.voxelSize[a], 4);
      }
      expect(m.normalLength[0]).toBeCloseTo(1, 5);
      expect(m.normalLength[1]).toBeCloseTo(1, 5);
      expect(m.alphaMode).toBe('OPAQUE');
      expect(m.doubleSided).toBe(true);
      expect((m.color as number[])[3]).toBe(1);
    });
    expect(read.meshes[0].color).not.toEqual(read.meshes[1].color);
  });

  it('neghip cut open: a clip box of whole cells is vtkExtractVOI + vtkMarchingCubes; a plane is vtkClipPolyData', () => {
    const file = join(sharedData, 'volumes/neghip_66x66x66_uint8.raw');
    const vtkFigures = JSON.parse(
      runPython(
        `
import sys, json, numpy as np, vtk
from vtk.util import numpy_support
vtk.vtkObject.GlobalWarningDisplayOff()
f = np.fromfile(sys.argv[1], np.uint8).reshape(66, 66, 66)
img = vtk.vtkImageData(); img.SetDimensions(66, 66, 66)
img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(f.ravel().astype(np.float32), deep=True))
def area(port):
    tri = vtk.vtkTriangleFilter(); tri.SetInputConnection(port); tri.Update()
    mp = vtk.vtkMassProperties(); mp.SetInputConnection(tri.GetOutputPort()); mp.Update()
    return tri.GetOutput().GetNumberOfCells(), mp.GetSurfaceArea()
voi = vtk.vtkExtractVOI(); voi.SetInputData(img); voi.SetVOI(10, 50, 12, 40, 8, 60)
mc = vtk.vtkMarchingCubes(); mc.SetInputConnection(voi.GetOutputPort()); mc.SetValue(0, 40.5); mc.Update()
whole = vtk.vtkMarchingCubes(); whole.SetInputData(img); whole.SetValue(0, 40.5)
n = np.array([1, 0.5, 0.2]); plane = vtk.vtkPlane(); plane.SetNormal(*n); plane.SetOrigin(*(n * 30 / n.dot(n)))
clip = vtk.vtkClipPolyData(); clip.SetInputConnection(whole.GetOutputPort()); clip.SetClipFunction(plane)
print(json.dumps({'box': [mc.GetOutput().GetNumberOfCells(), area(mc.GetOutputPort())[1]], 'plane': area(clip.GetOutputPort())}))
`,
        [file],
      ),
    );
    const run = (...clipArgs: string[]) => {
      const out = join(dir, `clip${clipArgs[0]}.json`);
      const r = cli('extract', file, '--iso', '40.5', '--rate', '20', ...clipArgs, '--json', out);
      expect(r.status, r.stderr).toBe(0);
      return (JSON.parse(readFileSync(out, 'utf8')).isosurfaces as (Rec & { clippedTriangles: number })[])[0];
    };
    const box = run('--clip', '10,12,8,50,40,60');
    expect(box.clippedTriangles).toBe(vtkFigures.box[0]);
    expect(Math.abs(box.area / vtkFigures.box[1] - 1)).toBeLessThan(1e-6);
    expect(box.enclosedVolume).toBeNull(); // cut open
    const plane = run('--plane', '1,0.5,0.2,30');
    expect(Math.abs(plane.area / vtkFigures.plane[1] - 1)).toBeLessThan(0.005);
    expect(plane.clippedTriangles).toBeLessThan(plane.triangles);
    // a box outside the volume or a plane with no direction: refused, saying why
    const outside = cli('extract', file, '--iso', '40.5', '--clip', '70,0,0,80,10,10');
    expect(outside.status).toBe(1);
    expect(outside.stderr).toMatch(/--clip 70,0,0,80,10,10: the box holds no cell of the volume/);
    const flat = cli('extract', file, '--iso', '40.5', '--plane', '0,0,0,1');
    expect(flat.status).toBe(2);
    expect(flat.stderr).toMatch(/the normal \(nx, ny, nz\) is zero/);
  });

  it('neghip: area and volume of closed surfaces as vtkMassProperties', () => {
    const file = join(sharedData, 'volumes/neghip_66x66x66_uint8.raw');
    const isos = [40.5, 120.5];
    const vtkFigures = JSON.parse(
      runPython(
        `${VTK_MEASURE}
f = np.fromfile(sys.argv[1], np.uint8).reshape(66, 66, 66)
print(json.dumps(measure(f, (1, 1, 1), ${JSON.stringify(isos)})))
`,
        [file],
      ),
    );
    const out = join(dir, 'neghip.json');
    const r = cli('extract', file, '--iso', isos.join(','), '--rate', '20', '--json', out);
    expect(r.status, r.stderr).toBe(0);
    const result = JSON.parse(readFileSync(out, 'utf8'));
    // both over one cache; the GPU's peak holds at least the stream and both surfaces' cache and vertices
    expect(result.drawnTogether).toEqual(isos);
    expect(result.gpuPeakBytes).toBeGreaterThan(66 ** 3);
    const recs = result.isosurfaces as Rec[];
    recs.forEach((rec, i) => {
      const v = vtkFigures[i];
      expect(rec.triangles).toBe(v.triangles);
      expect(v.boundaryEdges).toBe(0);
      expect(rec.openEdges).toBe(0);
      expect(Math.abs(rec.area / v.area - 1)).toBeLessThan(1e-3);
      expect(Math.abs(rec.enclosedVolume! / v.volume - 1)).toBeLessThan(1e-3);
    });
  });
});
