"""Opening an input as a lazy (z, y, x) dask array: which reader, from the
name and the first bytes. See converter/README.md for the forms accepted."""
from __future__ import annotations

import os

from .base import InputError, Volume
from .formats import is_zarr, open_generated, open_hdf5, open_netcdf, open_zarr
from .raw import open_nrrd, open_raw
from .tiff import TIFF_EXT, open_tiff, tiff_files
from .zfp import MAGIC as ZFP_MAGIC, open_zfp
from .series import Series, open_series  # noqa: E402  (series opens each file with open_input below)

__all__ = ["InputError", "Series", "Volume", "open_input", "open_series"]

_H5_EXT = (".h5", ".hdf5", ".he5", ".hdf")
_NC_EXT = (".nc", ".nc4", ".netcdf", ".cdf")


def _split_inner(spec: str) -> tuple[str, str | None]:
    """`file.h5:/path`, `file.nc:var`, `store.zarr:array` -> (file, inner)."""
    if os.path.exists(spec) or ":" not in spec:
        return spec, None
    path, inner = spec.rsplit(":", 1)
    return path, inner or None


def open_input(spec: str, chunk: int, work_dir: str, dims=None, dtype=None) -> Volume:
    if spec.startswith("gen:"):
        return open_generated(spec, chunk)
    path, inner = _split_inner(spec)
    if any(c in path for c in "*?[") or (os.path.isdir(path) and not is_zarr(path)):
        if not tiff_files(path):
            raise InputError(f"{spec}: no TIFF files there")
        return open_tiff(path, chunk)
    if is_zarr(path):
        return open_zarr(path, inner, chunk)
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if not os.path.isfile(path):
        raise InputError(f"{path}: not a file")
    try:
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError as e:
        raise InputError(f"{path}: cannot be read ({e.strerror})") from None
    lower = path.lower()
    if head.startswith(ZFP_MAGIC) or lower.endswith(".zfp"):
        return open_zfp(path, chunk)
    if head.startswith(b"NRRD000"):
        return open_nrrd(path, chunk, work_dir)
    if head[:4] in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+") or lower.endswith(TIFF_EXT):
        return open_tiff(path, chunk)
    if head.startswith(b"CDF") or lower.endswith(_NC_EXT):
        return open_netcdf(path, inner, chunk)
    if head.startswith(b"\x89HDF") or lower.endswith(_H5_EXT):
        return open_hdf5(path, inner, chunk)
    if inner:
        raise InputError(f"{path}: ':{inner}' names a part of an HDF5, NetCDF or Zarr input; this is none of them")
    return open_raw(path, chunk, dims=dims, dtype=dtype)
