#!/usr/bin/env python3
"""Times VTK's isosurface filters on a float32 volume, for benchmarks/isosurface.ts.

  vtk_flying_edges.py RAW X Y Z --iso a b c ... [--repeats N] [--filter flying-edges|marching-cubes]
                      [--backend STDThread|Sequential|...]

RAW is float32, little endian, x fastest (what our decoder writes). The image
is built once; for each isovalue the filter (normals, gradients and scalars
off, as in shared/data/reference/mc.json) is run N times and the median of the
Update() wall times is reported, with the triangle count. Prints JSON:
{"filter", "threads", "vtk", "results": [{"iso", "triangles", "ms", "samples"}]}.
vtkFlyingEdges3D runs in parallel through vtkSMPTools; the pip wheel defaults
to the Sequential backend, so STDThread (all cores) is selected unless
--backend says otherwise: "backend" and "threads" say what ran.
"""
import argparse
import json
import statistics
import time

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk


def main():
    p = argparse.ArgumentParser()
    p.add_argument('raw')
    p.add_argument('dims', type=int, nargs=3)
    p.add_argument('--iso', type=float, nargs='+', required=True)
    p.add_argument('--repeats', type=int, default=3)
    p.add_argument('--filter', choices=['flying-edges', 'marching-cubes'], default='flying-edges')
    p.add_argument('--backend', default='STDThread')
    a = p.parse_args()
    if not vtk.vtkSMPTools.SetBackend(a.backend):
        raise SystemExit(f'vtkSMPTools has no backend {a.backend}')
    nx, ny, nz = a.dims
    values = np.fromfile(a.raw, dtype='<f4')
    if values.size != nx * ny * nz:
        raise SystemExit(f'{a.raw}: {values.size} values for {nx}x{ny}x{nz}')
    image = vtk.vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(1, 1, 1)
    image.SetOrigin(0, 0, 0)
    scalars = numpy_to_vtk(values, deep=True)
    scalars.SetName('s')
    image.GetPointData().SetScalars(scalars)
    results = []
    for iso in a.iso:
        samples = []
        triangles = 0
        for _ in range(a.repeats):
            f = vtk.vtkFlyingEdges3D() if a.filter == 'flying-edges' else vtk.vtkMarchingCubes()
            f.SetInputData(image)
            f.SetValue(0, float(np.float32(iso)))
            f.ComputeNormalsOff()
            f.ComputeGradientsOff()
            f.ComputeScalarsOff()
            t0 = time.perf_counter()
            f.Update()
            samples.append((time.perf_counter() - t0) * 1000)
            triangles = f.GetOutput().GetNumberOfCells()
        results.append({'iso': iso, 'triangles': int(triangles), 'ms': statistics.median(samples), 'samples': samples})
    print(json.dumps({
        'filter': 'vtkFlyingEdges3D' if a.filter == 'flying-edges' else 'vtkMarchingCubes',
        'threads': vtk.vtkSMPTools.GetEstimatedNumberOfThreads(),
        'backend': vtk.vtkSMPTools.GetBackend(),
        'vtk': vtk.vtkVersion.GetVTKVersion(),
        'results': results,
    }))


if __name__ == '__main__':
    main()
