"""HDF5 datasets (h5py), NetCDF variables (xarray), Zarr arrays (zarr-python,
any codec), and a generated test volume."""
from __future__ import annotations

import json
import os
import threading

import dask.array as da
import numpy as np

from .base import InputError, LazySource, Volume, check_volume, file_identity, lazy_array
from .raw import unit_name


class H5Source(LazySource):
    def __init__(self, path: str, dataset: str, shape, dtype):
        self.path, self.dataset, self.shape, self.dtype = path, dataset, tuple(shape), np.dtype(dtype)

    def read(self, key):
        import h5py

        with h5py.File(self.path, "r") as f:
            d = f[self.dataset]
            full = (slice(None),) * (d.ndim - 3) + tuple(key)
            return np.asarray(d[full]).reshape(tuple(k.stop - k.start for k in key))


def open_hdf5(path: str, dataset: str | None, chunk: int) -> Volume:
    import h5py

    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise InputError(f"{path}: not a readable HDF5 file ({e})") from None
    with f:
        if not dataset:
            names = []
            f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) and o.ndim >= 3 else None)
            if len(names) != 1:
                raise InputError(f"{path}: name the dataset as {path}:/path/to/dataset (3D datasets: {names or 'none'})")
            dataset = names[0]
        if dataset not in f or not isinstance(f[dataset], h5py.Dataset):
            raise InputError(f"{path}: no dataset '{dataset}'")
        d = f[dataset]
        shape, dtype = check_volume(f"{path}:{dataset}", d.shape, d.dtype)
    src = H5Source(path, dataset, shape, dtype)
    arr = lazy_array(src, (chunk,) * 3, (file_identity(path), dataset))
    return Volume(arr, f"{path}:{dataset}", "hdf5")


# The netCDF-C library is not thread-safe: two of Dask's threads opening or
# closing a file at once failed with "NetCDF: HDF error". One read at a time
# per process (h5py holds its own lock; a cluster's processes each have theirs).
_NETCDF_LOCK = threading.Lock()


class NetcdfSource(LazySource):
    def __init__(self, path: str, variable: str, shape, dtype):
        self.path, self.variable, self.shape, self.dtype = path, variable, tuple(shape), np.dtype(dtype)

    def read(self, key):
        import xarray as xr

        with _NETCDF_LOCK, xr.open_dataset(self.path, cache=False, mask_and_scale=False) as ds:
            v = ds[self.variable]
            full = (0,) * (v.ndim - 3) + tuple(key)
            return np.asarray(v[full].values)


def open_netcdf(path: str, variable: str | None, chunk: int) -> Volume:
    import xarray as xr

    try:
        ds = xr.open_dataset(path, cache=False, mask_and_scale=False)
    except Exception as e:  # xarray raises many kinds for unreadable files
        raise InputError(f"{path}: not a readable NetCDF file ({e})") from None
    with ds:
        if not variable:
            names = [n for n, v in ds.data_vars.items() if v.ndim >= 3]
            if len(names) != 1:
                raise InputError(f"{path}: name the variable as {path}:variable (3D variables: {names or 'none'})")
            variable = names[0]
        if variable not in ds.data_vars:
            raise InputError(f"{path}: no variable '{variable}' (variables: {list(ds.data_vars)})")
        v = ds[variable]
        shape, dtype = check_volume(f"{path}:{variable}", v.shape, v.dtype)
        if any(n != 1 for n in v.shape[:-3]):
            raise InputError(f"{path}:{variable}: shape {v.shape}; a volume has 3 axes")
        voxel, units = [], set()
        for dim in v.dims[-3:][::-1]:  # x, y, z
            c = ds.coords.get(dim)
            if c is not None and c.ndim == 1 and c.size >= 2 and np.issubdtype(c.dtype, np.number):
                step = np.diff(np.asarray(c.values, dtype=np.float64))
                if np.allclose(step, step[0]) and step[0] != 0:
                    voxel.append(abs(float(step[0])))
                    units.add(str(c.attrs.get("units", "")))
    src = NetcdfSource(path, variable, shape, dtype)
    arr = lazy_array(src, (chunk,) * 3, (file_identity(path), variable))
    vol = Volume(arr, f"{path}:{variable}", "netcdf")
    if len(voxel) == 3:
        vol.voxel_size = tuple(voxel)
        if len(units) == 1 and "" not in units:
            vol.unit = unit_name(units.pop())
    return vol


def open_zarr_node(path: str, inner: str | None):
    """The Zarr array at path[:inner] (an OME-Zarr group: its first dataset), and its name in messages."""
    import zarr

    try:
        node = zarr.open(path, mode="r")
        if inner:
            node = node[inner]
        if isinstance(node, zarr.Group):
            ome = node.attrs.get("ome", {}).get("multiscales") or node.attrs.get("multiscales")
            if not ome:
                raise InputError(f"{path}: a Zarr group; name the array as {path}:array/path")
            inner = f"{inner + '/' if inner else ''}{ome[0]['datasets'][0]['path']}"
            node = node[ome[0]["datasets"][0]["path"]]
    except InputError:
        raise
    except Exception as e:  # zarr raises many kinds for stores it cannot open
        raise InputError(f"{path}: not a readable Zarr array ({e})") from None
    return node, (f"{path}:{inner}" if inner else path)


def open_zarr(path: str, inner: str | None, chunk: int) -> Volume:
    node, name = open_zarr_node(path, inner)
    shape, dtype = check_volume(name, node.shape, node.dtype)
    arr = da.from_zarr(node)
    if arr.ndim > 3:
        arr = arr.reshape(shape)
    return Volume(arr, name, "zarr")


def generated_block(block_info=None):
    """A smooth field with finer detail, a pure function of the voxel's
    position (so any chunking, on any scheduler, gives the same values); a sum
    of products of 1-D waves, cheap enough not to dominate a benchmark."""
    loc = block_info[None]["array-location"]
    shape = block_info[None]["shape"]
    z, y, x = (np.arange(a, b, dtype=np.float64) / n for (a, b), n in zip(loc, shape))
    wave = lambda t, f, p: np.sin(f * t + p).astype(np.float32)  # noqa: E731
    zs, ys, xs = (slice(None), None, None), (None, slice(None), None), (None, None, slice(None))
    f = wave(x, 6.3, 0.2)[xs] * wave(y, 4.1, 1.0)[ys]
    f = f + wave(y, 5.3, 0.7)[ys] * wave(z, 3.7, 2.0)[zs]
    f = f + wave(z, 7.9, 1.3)[zs] * wave(x, 2.9, 0.4)[xs]
    n = np.asarray(shape, dtype=np.float64)
    f = f + 0.05 * (wave(x, 0.9 * n[2], 0.0)[xs] * wave(y, 0.7 * n[1], 0.0)[ys] * wave(z, 1.1 * n[0], 0.0)[zs])
    return np.ascontiguousarray(f, dtype=np.float32)


def open_generated(spec: str, chunk: int) -> Volume:
    """`gen:XxYxZ`: a synthetic float32 volume computed chunk by chunk (tests, benchmarks, cluster trials)."""
    try:
        dims = [int(v) for v in spec.split(":", 1)[1].split("x")]
    except ValueError:
        dims = []
    if len(dims) != 3:
        raise InputError(f"{spec}: a generated volume is written gen:XxYxZ")
    shape, _ = check_volume(spec, (dims[2], dims[1], dims[0]), np.float32)
    arr = da.map_blocks(generated_block, chunks=da.core.normalize_chunks((chunk,) * 3, shape), dtype=np.float32,
                        meta=np.empty((0, 0, 0), np.float32), name=f"generated-{dims[0]}x{dims[1]}x{dims[2]}")
    return Volume(arr, spec, "generated")


def is_zarr(path: str) -> bool:
    return os.path.isdir(path) and any(
        os.path.exists(os.path.join(path, f)) for f in ("zarr.json", ".zarray", ".zgroup"))


def read_json(path: str):
    with open(path) as f:
        return json.load(f)
