"""TIFF stacks with tifffile: one multi-page file (classic or BigTIFF, ImageJ
hyperstacks too) or many single-page files (a folder, a glob, in natural order)."""
from __future__ import annotations

import glob
import os
import re

import numpy as np
import tifffile

from .base import InputError, LazySource, Volume, check_volume, lazy_array, slab_depth
from .raw import unit_name

TIFF_EXT = (".tif", ".tiff", ".btf", ".tf8")


def natural_key(s: str):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def tiff_files(spec: str) -> list[str]:
    if os.path.isdir(spec):
        files = [os.path.join(spec, f) for f in os.listdir(spec) if f.lower().endswith(TIFF_EXT)]
    elif any(c in spec for c in "*?["):
        files = glob.glob(spec)
    else:
        files = [spec]
    return sorted(files, key=natural_key)


class TiffStackSource(LazySource):
    """Plane z is page `pages[z]` of file `files[z]` (one file, or one per plane)."""

    def __init__(self, files: list[str], pages: list[int] | None, shape, dtype):
        self.files, self.pages, self.shape, self.dtype = files, pages, tuple(shape), np.dtype(dtype)

    def read(self, key):
        zs, ys, xs = key
        out = np.empty((zs.stop - zs.start, ys.stop - ys.start, xs.stop - xs.start), dtype=self.dtype)
        if self.pages is not None:
            plane = tifffile.imread(self.files[0], key=list(range(zs.start, zs.stop)))
            plane = plane.reshape(out.shape[0], self.shape[1], self.shape[2])
            out[:] = plane[:, ys, xs]
        else:
            for i, z in enumerate(range(zs.start, zs.stop)):
                out[i] = tifffile.imread(self.files[z], key=0)[ys, xs]
        return out


def _calibration(tif: tifffile.TiffFile):
    """Voxel size (x, y, z) and unit from ImageJ metadata and the resolution tags."""
    page = tif.pages[0]
    ij = tif.imagej_metadata or {}
    try:
        xres = page.tags["XResolution"].value
        yres = page.tags["YResolution"].value
        sx, sy = xres[1] / xres[0], yres[1] / yres[0]
    except (KeyError, ZeroDivisionError, TypeError, IndexError):
        return None, None
    unit = None
    if ij.get("unit"):
        unit = unit_name(str(ij["unit"]).replace("\\u00B5", "u"))
    else:
        ru = page.tags.get("ResolutionUnit")
        unit = {2: "inch", 3: "centimeter"}.get(int(ru.value) if ru else 1)
        if unit is None:
            return None, None
    sz = float(ij.get("spacing", 1.0 if unit is None else sx))
    if not (sx > 0 and sy > 0 and sz > 0):
        return None, None
    return (float(sx), float(sy), sz), unit


def open_tiff(spec: str, chunk: int) -> Volume:
    files = tiff_files(spec)
    if not files:
        raise InputError(f"{spec}: no TIFF files found")
    try:
        with tifffile.TiffFile(files[0]) as tif:
            series = tif.series[0]
            shape, dtype = series.shape, series.dtype
            voxel, unit = _calibration(tif)
    except (tifffile.TiffFileError, OSError, ValueError, IndexError, KeyError) as e:
        raise InputError(f"{files[0]}: not a readable TIFF ({e})") from None
    if len(files) == 1:
        shape = tuple(shape)
        if len(shape) == 2:
            shape = (1, *shape)
        shape, dtype = check_volume(files[0], shape, dtype)
        src = TiffStackSource(files, list(range(shape[0])), shape, dtype)
        source = files[0]
    else:
        if len(shape) != 2:
            raise InputError(f"{files[0]}: a stack of files needs one 2D image per file, this one has shape {tuple(shape)}")
        for f in files[1:]:
            try:
                with tifffile.TiffFile(f) as t:
                    p = t.pages[0]
                    if tuple(p.shape) != tuple(shape) or p.dtype != dtype:
                        raise InputError(f"{f}: image {tuple(p.shape)} {p.dtype}, the stack's first file has "
                                         f"{tuple(shape)} {dtype}")
            except (tifffile.TiffFileError, OSError, ValueError, IndexError) as e:
                raise InputError(f"{f}: not a readable TIFF ({e})") from None
        shape, dtype = check_volume(files[0], (len(files), *shape), dtype)
        src = TiffStackSource(files, None, shape, dtype)
        source = f"{files[0]} .. {os.path.basename(files[-1])} ({len(files)} files)"
    depth = slab_depth(chunk, shape[1] * shape[2] * dtype.itemsize)
    identity = [(os.path.abspath(f), os.path.getsize(f), os.stat(f).st_mtime_ns) for f in files]
    arr = lazy_array(src, (depth, shape[1], shape[2]), identity)
    return Volume(arr, source, "tiff", voxel_size=voxel, unit=unit)
