"""A time series (`--time`): one volume per time point, each a lazy (z, y, x)
dask array. Either files matched by a pattern ('run/step_*.raw'), in name
order, each opened as a single input is (any form), all of one shape and
type; or one Zarr array of 4 axes, read as t, z, y, x."""
from __future__ import annotations

import glob
import os
from dataclasses import dataclass

from .base import InputError, Volume, check_volume
from .formats import is_zarr, open_zarr_node

MAX_TIME_POINTS = 1 << 20


@dataclass
class Series:
    volumes: list[Volume]  # one per time point, in order
    source: str  # the pattern or the 4-D input, for messages and the store's attributes
    files: list[str] | None  # the files matched (a pattern), in order

    def close(self) -> None:
        for v in self.volumes:
            v.close()


def _shape_text(shape, dtype) -> str:
    return f"{shape[2]}x{shape[1]}x{shape[0]} {dtype}"


def open_series(spec: str, chunk: int, work_dir: str, dims=None, dtype=None) -> Series:
    from . import _split_inner, open_input

    if any(c in spec for c in "*?["):
        files = sorted(f for f in glob.glob(spec) if os.path.isfile(f))
        if not files:
            raise InputError(f"{spec}: no files match the pattern")
        if len(files) > MAX_TIME_POINTS:
            raise InputError(f"{spec}: {len(files)} files, more time points than this converter handles ({MAX_TIME_POINTS})")
        volumes: list[Volume] = []
        try:
            for i, f in enumerate(files):
                v = open_input(f, chunk, os.path.join(work_dir, str(i)), dims=dims, dtype=dtype)
                volumes.append(v)
                first = volumes[0].array
                if v.array.shape != first.shape or v.array.dtype != first.dtype:
                    raise InputError(
                        f"{f}: {_shape_text(v.array.shape, v.array.dtype)}, but {files[0]} (time point 0) is "
                        f"{_shape_text(first.shape, first.dtype)}; every time point of a series has one shape and type"
                    )
        except BaseException:
            for v in volumes:
                v.close()
            raise
        return Series(volumes, spec, files)
    path, inner = _split_inner(spec)
    if not is_zarr(path):
        raise InputError(
            f"{spec}: with --time, give a pattern of files, one time point each in name order ('run/step_*.raw'), "
            "or a Zarr array of 4 axes (t, z, y, x)"
        )
    return _zarr_series(path, inner)


def _zarr_series(path: str, inner: str | None) -> Series:
    import dask.array as da

    node, name = open_zarr_node(path, inner)
    shape = tuple(int(n) for n in node.shape)
    while len(shape) > 4 and shape[0] == 1:
        shape = shape[1:]
    if len(shape) != 4:
        raise InputError(f"{name}: shape {shape}; a time series in one array has 4 axes (t, z, y, x)")
    t = shape[0]
    if t < 1 or t > MAX_TIME_POINTS:
        raise InputError(f"{name}: {t} time points; this converter takes 1 to {MAX_TIME_POINTS}")
    zyx, _ = check_volume(name, shape[1:], node.dtype)
    arr = da.from_zarr(node)
    if arr.ndim != 4:
        arr = arr.reshape(shape)
    volumes = [Volume(arr[i], f"{name}[{i}]", "zarr") for i in range(t)]
    return Series(volumes, name, None)
