"""The store's metadata: the Zarr v3 group and its arrays, OME-Zarr 0.5
multiscales, our own attributes (parameters, completeness, ranges, histogram),
and the decision to create, resume, or refuse an existing store."""
from __future__ import annotations

import json
import os
import warnings

import numpy as np
import zarr
from zarr.codecs.numcodecs import ZFPY

from .inputs import InputError
from .layout import RANGES_GROUP, level_path, ranges_path

ATTR = "zfpzarr"  # our attributes' key in the group's zarr.json
FORMAT_VERSION = 1
ZFP_MODE_FIXED_RATE = 2

warnings.filterwarnings("ignore", message="Numcodecs codecs are not in the Zarr version 3 specification")


def group_attributes(out: str) -> dict | None:
    """The group's attributes, or None when `out` holds no Zarr group."""
    meta = os.path.join(out, "zarr.json")
    if not os.path.isfile(meta):
        return None
    try:
        with open(meta) as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError):
        return None
    return doc.get("attributes", {}) if doc.get("node_type") == "group" else None


def plan_store(out: str, params: dict, overwrite: bool) -> str:
    """'create', 'resume' or 'complete' (nothing to do); InputError when the
    path holds something else (naming it)."""
    if not os.path.exists(out):
        return "create"
    if not os.path.isdir(out):
        raise InputError(f"{out}: exists and is not a folder")
    attrs = group_attributes(out)
    ours = (attrs or {}).get(ATTR)
    if ours is None:
        if os.listdir(out):
            raise InputError(f"{out}: exists and is not a store made by this converter (remove it or choose another --out)")
        return "create"
    if ours.get("params") != params:
        if overwrite:
            return "create"
        raise InputError(f"{out}: a store made from another input or with other settings "
                         "(remove it, choose another --out, or --overwrite)")
    return "complete" if ours.get("complete") else "resume"


def ome_multiscales(name: str, shapes, voxel_size, unit, time: dict | None = None) -> dict:
    """OME-Zarr 0.5 `multiscales`: axes z, y, x; per level a scale (voxel size
    times 2^level) and a translation (a coarse voxel's centre is the mean of
    the fine voxels it covers). A time series (`time`: step, unit) has a
    first axis t, of scale `step` and translation 0 on every level."""
    vx = tuple(voxel_size) if voxel_size else (1.0, 1.0, 1.0)
    zyx = (vx[2], vx[1], vx[0])
    axes = []
    if time is not None:
        t_axis = {"name": "t", "type": "time"}
        if time.get("unit"):
            t_axis["unit"] = time["unit"]
        axes.append(t_axis)
    t_scale = [float(time["step"])] if time is not None else []
    t_shift = [0.0] if time is not None else []
    for a in ("z", "y", "x"):
        axis = {"name": a, "type": "space"}
        if unit:
            axis["unit"] = unit
        axes.append(axis)
    datasets = []
    for level in range(len(shapes)):
        f = 2**level
        datasets.append({
            "path": level_path(level),
            "coordinateTransformations": [
                {"type": "scale", "scale": [*t_scale, *(s * f for s in zyx)]},
                {"type": "translation", "translation": [*t_shift, *(s * (f - 1) / 2 for s in zyx)]},
            ],
        })
    return {
        "version": "0.5",
        "multiscales": [{
            "name": name,
            "axes": axes,
            "datasets": datasets,
            "type": "mean",
            "metadata": {"description": "mean of each 2x2x2 cell; fewer voxels at odd edges", "method": "zfpzarr.levels.mean2"},
        }],
    }


def create_store(out: str, params: dict, shapes, rates, chunk: int, shard: int | None, ome: dict, extra: dict,
                 time_points: int | None = None) -> None:
    """The group and its empty arrays. A time series (`time_points` T): each
    level (T, z, y, x) in chunks of one time point (1, C, C, C), each chunk
    still one 3-D zfp stream; each range array (T, cz, cy, cx, 2)."""
    if os.path.exists(out):
        import shutil

        shutil.rmtree(out)
    attrs = {"ome": ome, ATTR: {"format": FORMAT_VERSION, "complete": False, "params": params, **extra}}
    group = zarr.create_group(store=out, zarr_format=3, attributes=attrs)
    t_shape = (time_points,) if time_points else ()
    t_chunk = (1,) if time_points else ()
    t_name = ["t"] if time_points else []
    for level, (shape, rate) in enumerate(zip(shapes, rates)):
        group.create_array(
            name=level_path(level), shape=(*t_shape, *shape), chunks=(*t_chunk, *(chunk,) * 3),
            shards=(*t_chunk, *(chunk * shard,) * 3) if shard else None, dtype="float32",
            serializer=ZFPY(mode=ZFP_MODE_FIXED_RATE, rate=rate), compressors=None, filters=None,
            fill_value=0.0, dimension_names=[*t_name, "z", "y", "x"],
        )
    ranges = group.create_group(RANGES_GROUP)
    for level, shape in enumerate(shapes):
        grid = tuple(-(-n // chunk) for n in shape)
        ranges.create_array(
            name=str(level), shape=(*t_shape, *grid, 2), chunks=(*t_chunk, *(min(g, 64) for g in grid), 2),
            dtype="float32", compressors=None, filters=None, fill_value=float("nan"),
            dimension_names=[*t_name, "z", "y", "x", "minmax"],
        )


def write_ranges(out: str, level: int, ranges: np.ndarray, time: int | None = None) -> None:
    arr = zarr.open_array(store=out, path=ranges_path(level), mode="r+")
    if time is None:
        arr[...] = ranges
    else:
        arr[time] = ranges


def finish_store(out: str, result: dict) -> None:
    """Writes what the reader needs last, then marks the store complete."""
    group = zarr.open_group(store=out, mode="r+")
    ours = dict(group.attrs[ATTR])
    ours.update(result)
    ours["complete"] = True
    group.attrs[ATTR] = ours


def histogram_level(shapes, max_voxels: int = 256**3) -> int:
    for level, s in enumerate(shapes):
        if s[0] * s[1] * s[2] <= max_voxels:
            return level
    return len(shapes) - 1
