#!/usr/bin/env python3
"""Reference helpers for the marching-cubes tests (run with the project's .venv python).

  mc-reference.py decode ZFP OUT.raw [--precision P --dims X Y Z]
      zfpy-decode a zfp stream to float32 raw (C order [z][y][x]). With a header the
      stream describes itself; a headerless fixed-precision stream (the open-scivis
      `_float8.zfp` files) needs --precision and --dims. Prints {"dims", "sha256"}.

  mc-reference.py vtk-soup IN.raw X Y Z ISO OUT.raw
      vtkMarchingCubes (normals, gradients, scalars off) on a float32 volume; writes
      its triangles as a float32 soup (xyz per vertex, 3 vertices per triangle, VTK's
      vertex order). Prints {"triangles", "points"}.
"""
import argparse
import hashlib
import json
import sys

import numpy as np


def decode(args):
    import zfpy
    buf = open(args.zfp, 'rb').read()
    if args.precision is None:
        a = zfpy.decompress_numpy(buf)
    else:
        if not args.dims:
            raise SystemExit('--dims X Y Z is needed for a headerless stream')
        x, y, z = args.dims
        # zfpy takes the shape slowest axis first.
        a = zfpy._decompress(buf, zfpy.type_float, [z, y, x], precision=args.precision)
    a = np.ascontiguousarray(a, dtype=np.float32)
    if a.ndim != 3:
        raise SystemExit(f'expected a 3D field, got shape {a.shape}')
    raw = a.tobytes()
    with open(args.out, 'wb') as f:
        f.write(raw)
    nz, ny, nx = a.shape
    print(json.dumps({'dims': [nx, ny, nz], 'sha256': hashlib.sha256(raw).hexdigest()}))


def vtk_soup(args):
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    nx, ny, nz = args.dims
    a = np.fromfile(args.raw, dtype='<f4')
    if a.size != nx * ny * nz:
        raise SystemExit(f'{args.raw}: {a.size} values for {nx}x{ny}x{nz}')
    im = vtk.vtkImageData()
    im.SetDimensions(nx, ny, nz)
    im.SetSpacing(1, 1, 1)
    im.SetOrigin(0, 0, 0)
    arr = numpy_to_vtk(a, deep=True)
    arr.SetName('s')
    im.GetPointData().SetScalars(arr)
    mc = vtk.vtkMarchingCubes()
    mc.SetInputData(im)
    mc.SetValue(0, float(np.float32(args.iso)))
    mc.ComputeNormalsOff()
    mc.ComputeGradientsOff()
    mc.ComputeScalarsOff()
    mc.Update()
    out = mc.GetOutput()
    if out.GetNumberOfPoints() == 0:
        soup = np.zeros((0, 3), np.float32)
        ntri = 0
    else:
        pts = vtk_to_numpy(out.GetPoints().GetData()).astype(np.float32)
        polys = out.GetPolys()
        conn = vtk_to_numpy(polys.GetConnectivityArray())
        offs = vtk_to_numpy(polys.GetOffsetsArray())
        if not np.all(np.diff(offs) == 3):
            raise SystemExit('vtkMarchingCubes output has non-triangle cells')
        soup = pts[conn]
        ntri = len(offs) - 1
    soup.astype('<f4').tofile(args.out)
    print(json.dumps({'triangles': int(ntri), 'points': int(out.GetNumberOfPoints())}))


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest='cmd', required=True)
    d = sub.add_parser('decode')
    d.add_argument('zfp')
    d.add_argument('out')
    d.add_argument('--precision', type=int)
    d.add_argument('--dims', type=int, nargs=3)
    v = sub.add_parser('vtk-soup')
    v.add_argument('raw')
    v.add_argument('dims', type=int, nargs=3)
    v.add_argument('iso', type=float)
    v.add_argument('out')
    args = ap.parse_args()
    decode(args) if args.cmd == 'decode' else vtk_soup(args)
    return 0


if __name__ == '__main__':
    sys.exit(main())
