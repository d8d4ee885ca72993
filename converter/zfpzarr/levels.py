"""Coarser levels: the mean of each 2x2x2 cell, on Dask.

At an odd edge the last cell has fewer voxels (1 or 2 along that axis) and
is the mean of those it has. Sums are taken in float64, in a fixed order,
then divided by the count and rounded to float32 once.
"""
from __future__ import annotations

import dask.array as da
import numpy as np


def mean2(block: np.ndarray) -> np.ndarray:
    z, y, x = block.shape
    out_shape = ((z + 1) // 2, (y + 1) // 2, (x + 1) // 2)
    total = np.zeros(out_shape, dtype=np.float64)
    count = np.zeros(out_shape, dtype=np.float64)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                part = block[dz::2, dy::2, dx::2]
                region = (slice(0, part.shape[0]), slice(0, part.shape[1]), slice(0, part.shape[2]))
                total[region] += part
                count[region] += 1
    return (total / count).astype(np.float32)


def downsample(level: da.Array, chunk: int) -> da.Array:
    """The next level of a (z, y, x) float32 array chunked by `chunk`."""
    # Pairs of chunks merged: every merged block starts at an even voxel, so
    # the cells never straddle blocks; only the last block can be odd.
    merged = level.rechunk((2 * chunk,) * 3)
    out_chunks = tuple(tuple((n + 1) // 2 for n in c) for c in merged.chunks)
    return merged.map_blocks(mean2, chunks=out_chunks, dtype=np.float32)
