"""`--ranges-only STORE --out RANGES.zarr`: per-brick value ranges of a store
of lossless chunks that cannot be rewritten (someone else's OME-Zarr), so the
page (`&ranges=URL`) and the CLI (`--ranges PATH`) plan which bricks a surface
needs before fetching any.

The page reads such a store as bricks (src/store/zarr/source-store.ts): a
level's chunk when it is a cube with an edge a multiple of 4 (4..256), else
64^3 bricks, or the finer level's edge when those would not nest in its
bricks (brick_edge); each brick is compressed on the GPU at a rate (default 8). The
surface is made from the zfp-decoded values, so a brick's range here is the
range of its values compressed at that rate by zfpy and decoded (a source
range alone does not bound them): min and max over the brick's voxels inside
the array. Written: a Zarr v3 group with `ranges/<L>` float32 [gz, gy, gx, 2]
(the converter's layout) and attributes `zfpzarr_ranges` (the rate, the time
point and channel, and per level its path, brick edge and grid) that the page
checks against the store before using them.
"""
from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import zarr
import zfpy

from .chunks import padded_chunk
from .inputs import InputError

BRICK_EDGE = 64
ATTR = "zfpzarr_ranges"


def brick_edge(chunks_zyx: tuple[int, int, int], scale_zyx=(1, 1, 1), finer=None) -> int:
    """The page's rule (brick-edge.ts brickEdge): the chunk edge when chunks
    are cubes of 4..256 (a multiple of 4), else 64; but the finer level's edge
    when its bricks would not nest in this level's (`finer`: its edge and
    scale, z, y, x; a scale is level-0 voxels per voxel)."""
    cz, cy, cx = chunks_zyx
    edge = cx if cx == cy == cz and cx % 4 == 0 and 4 <= cx <= 256 else BRICK_EDGE
    if finer is None:
        return edge
    f_edge, f_scale = finer
    nests = all((edge * s) % (f_edge * fs) == 0 for s, fs in zip(scale_zyx, f_scale))
    return edge if nests else f_edge


def _levels(node, path: str):
    """(path in the store, array, scale z, y, x) per level, finest first."""
    if isinstance(node, zarr.Array):
        return [("", node, (1, 1, 1))], None
    attrs = dict(node.attrs)
    ms = (attrs.get("ome") or {}).get("multiscales") or attrs.get("multiscales")
    if not ms:
        raise InputError(f"{path}: a Zarr group without OME-Zarr multiscales")
    datasets, scales = pyramid_chain(ms[0]["datasets"])
    return [(d["path"], node[d["path"]], sc) for d, sc in zip(datasets, scales)], ms[0].get("axes")


def pyramid_chain(datasets: list) -> tuple[list, list]:
    """The page's rule (metadata.ts pyramidChain): level 0, then each dataset
    whose OME scale is a power of two times level 0's on every axis, at least
    the previous level's on every axis and more on one (levels may halve only
    some axes); the others are not levels the page draws. Without a scale on
    every dataset, all of them, level L at 2^L. With each, its scale (z, y, x:
    level-0 voxels per voxel)."""
    def scale(d):
        for t in d.get("coordinateTransformations") or []:
            if t.get("type") == "scale" and len(t.get("scale") or []) >= 3:
                v = [float(x) for x in t["scale"][-3:]]
                return v if all(x > 0 and math.isfinite(x) for x in v) else None
        return None
    scales = [scale(d) for d in datasets]
    if not datasets or any(s is None for s in scales):
        return list(datasets), [(2 ** L,) * 3 for L in range(len(datasets))]
    out = [datasets[0]]
    out_scales = [(1, 1, 1)]
    prev = [1.0, 1.0, 1.0]
    for d, s in zip(datasets[1:], scales[1:]):
        f = [a / b for a, b in zip(s, scales[0])]
        pow2 = [2.0 ** round(math.log2(v)) for v in f]
        exact = all(abs(v - p) <= 1e-6 * p for v, p in zip(f, pow2))
        if exact and all(p >= q for p, q in zip(pow2, prev)) and any(p > q for p, q in zip(pow2, prev)):
            out.append(d)
            out_scales.append(tuple(int(v) for v in pow2))
            prev = pow2
    return out, out_scales


def _spatial(path: str, shape, axes, time: int, channel: int):
    """Index tuple selecting the chosen time point / channel, and the spatial axes' positions (z, y, x)."""
    names = [a if isinstance(a, str) else a.get("name") for a in axes] if axes and len(axes) == len(shape) else None
    if names is None:
        names = (["t", "c", "z", "y", "x"])[-len(shape):] if len(shape) <= 5 else [f"d{i}" for i in range(len(shape))]
    if len(shape) < 3 or not all(n in names for n in "zyx"):
        raise InputError(f"{path}: shape {list(shape)} is not a 3-D volume")
    zyx = tuple(names.index(n) for n in "zyx")
    index = []
    for i, n in enumerate(names):
        if i in zyx:
            index.append(slice(None))
            continue
        v = time if n in ("t", "time") else channel if n in ("c", "channel") else 0
        if not 0 <= v < shape[i]:
            raise InputError(f"{path}: {n} index {v} is outside 0..{shape[i] - 1}")
        index.append(v)
    return index, zyx


def brick_range(arr, index, zyx, lo, n, edge: int, rate: float) -> tuple[float, float]:
    sel = list(index)
    for a, axis in enumerate(zyx):
        sel[axis] = slice(lo[a], lo[a] + n[a])
    values = np.asarray(arr[tuple(sel)])
    # the remaining axes are z, y, x in the array's order; bring them to z, y, x
    order = np.argsort(np.argsort([zyx[0], zyx[1], zyx[2]]))
    values = np.transpose(values, order).astype(np.float32)
    decoded = zfpy.decompress_numpy(zfpy.compress_numpy(padded_chunk(values, edge), rate=rate, write_header=True))
    valid = decoded[: n[0], : n[1], : n[2]]
    return float(valid.min()), float(valid.max())


def ranges_only(path: str, out: str, rate: float = 8.0, time: int = 0, channel: int = 0,
                workers: int | None = None, progress: bool = True) -> dict:
    try:
        node = zarr.open(path, mode="r")
    except Exception as e:  # zarr raises many kinds for stores it cannot open
        raise InputError(f"{path}: not a readable Zarr store ({e})") from None
    levels, axes = _levels(node, path)
    root = zarr.open_group(out, mode="w", zarr_format=3)
    meta = []
    with ThreadPoolExecutor(max_workers=workers or os.cpu_count()) as pool:
        finer = None
        for L, (p, arr, scale) in enumerate(levels):
            index, zyx = _spatial(f"{path} level {L}", arr.shape, axes, time, channel)
            dims = [arr.shape[a] for a in zyx]
            # bricks that nest in the finer level's (the view's cut refines every level)
            edge = brick_edge(tuple(arr.chunks[a] for a in zyx), scale, finer)
            finer = (edge, scale)
            grid = [-(-d // edge) for d in dims]  # z, y, x
            bricks = [(bz, by, bx) for bz in range(grid[0]) for by in range(grid[1]) for bx in range(grid[2])]

            def one(b, arr=arr, index=index, zyx=zyx, dims=dims, edge=edge):
                lo = [b[a] * edge for a in range(3)]
                n = [min(edge, dims[a] - lo[a]) for a in range(3)]
                return brick_range(arr, index, zyx, lo, n, edge, rate)

            out_ranges = np.array(list(pool.map(one, bricks)), dtype=np.float32).reshape(*grid, 2)
            root.create_array(f"ranges/{L}", data=out_ranges, chunks=out_ranges.shape)
            meta.append({"path": p, "brick": edge, "grid": [grid[2], grid[1], grid[0]], "dims": [dims[2], dims[1], dims[0]]})
            if progress:
                print(f"level {L}: {len(bricks)} bricks of {edge}^3, range {out_ranges[..., 0].min():g} .. {out_ranges[..., 1].max():g}")
    info = {"source": path, "rate": rate, "time": time, "channel": channel, "levels": meta}
    root.attrs[ATTR] = info
    return info
