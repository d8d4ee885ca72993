"""What every input reader gives: a lazy (z, y, x) dask array and what is known about it."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable

import dask.array as da
import numpy as np
from dask.base import tokenize

# Sample types a volume may have (converted to float32 for the store).
SUPPORTED_KINDS = "iuf"
MAX_VOXELS = 1 << 50


class InputError(Exception):
    """A bad input: the message names the file and says what is wrong."""


@dataclass
class Volume:
    array: da.Array  # (z, y, x), the input's own sample type
    source: str  # what was opened, for messages and the store's attributes
    kind: str
    voxel_size: tuple[float, float, float] | None = None  # x, y, z
    unit: str | None = None
    default_rate: float | None = None  # zfp inputs: their own rate
    cleanup: list[Callable[[], None]] = field(default_factory=list)

    def close(self) -> None:
        for f in self.cleanup:
            f()
        self.cleanup.clear()


class LazySource:
    """An array-like that opens its file on every read, so it pickles to
    Dask workers as a few strings and never holds the volume."""

    shape: tuple[int, ...]
    dtype: np.dtype
    ndim = 3

    def __getitem__(self, key):
        return self.read(key)

    def read(self, key) -> np.ndarray:  # pragma: no cover - implemented by readers
        raise NotImplementedError


def check_volume(path: str, shape, dtype) -> tuple[tuple[int, int, int], np.dtype]:
    """Drops leading axes of length 1; requires 3 axes of sane size and a numeric type."""
    shape = tuple(int(n) for n in shape)
    while len(shape) > 3 and shape[0] == 1:
        shape = shape[1:]
    if len(shape) != 3:
        raise InputError(f"{path}: a volume has 3 axes, this one has shape {shape}")
    if min(shape) < 1:
        raise InputError(f"{path}: empty volume, shape {shape}")
    if shape[0] * shape[1] * shape[2] > MAX_VOXELS:
        raise InputError(f"{path}: shape {shape} is beyond any volume this converter handles")
    dtype = np.dtype(dtype)
    if dtype.kind not in SUPPORTED_KINDS or dtype.itemsize > 8:
        raise InputError(f"{path}: sample type {dtype} is not supported (integers and floats are)")
    return shape, dtype


def slab_depth(chunk: int, plane_bytes: int, budget: int = 64 << 20) -> int:
    """Planes per read for readers that read whole planes: a divisor of the
    chunk edge, a multiple of 4 where possible, about `budget` bytes."""
    depth = chunk
    while depth > 4 and depth % 2 == 0 and depth * plane_bytes > budget:
        depth //= 2
    return depth


def lazy_array(source: LazySource, chunks, identity) -> da.Array:
    name = f"input-{tokenize(type(source).__name__, identity, chunks)}"
    shape = tuple(source.shape)
    while len(shape) > 3 and shape[0] == 1:
        shape = shape[1:]
    arr = da.from_array(source, chunks=chunks, asarray=True, fancy=False, lock=False, name=name,
                        meta=np.empty((0,) * len(source.shape), dtype=source.dtype))
    if arr.ndim > 3:
        arr = arr.reshape(shape)
    return arr


def file_identity(path: str) -> tuple:
    st = os.stat(path)
    return (os.path.abspath(path), st.st_size, st.st_mtime_ns)
