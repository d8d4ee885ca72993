"""Where things are in a store: levels, chunk grids, storage units, files.

A storage unit is what one file holds: a chunk, or (with --shard N) a shard
of N x N x N chunks. Shapes and indices are (z, y, x), as the arrays are.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

# Array names in the group (see converter/README.md, "Store layout").
RANGES_GROUP = "ranges"


def level_path(level: int) -> str:
    return str(level)


def ranges_path(level: int) -> str:
    return f"{RANGES_GROUP}/{level}"


def level_shapes(shape: tuple[int, int, int], chunk: int, levels: int | None) -> list[tuple[int, int, int]]:
    """Level 0 is `shape`; each next one is ceil(n / 2) per axis; `levels=None`
    goes on until the coarsest fits one chunk."""
    shapes = [tuple(int(n) for n in shape)]
    while True:
        if levels is not None and len(shapes) >= levels:
            break
        if levels is None and max(shapes[-1]) <= chunk:
            break
        if max(shapes[-1]) == 1:
            break
        shapes.append(tuple((n + 1) // 2 for n in shapes[-1]))
    return shapes


@dataclass(frozen=True)
class LevelLayout:
    store: str
    level: int
    shape: tuple[int, int, int]
    chunk: int
    rate: float
    shard: int | None = None
    time: int | None = None  # a time series: the time point this layout writes (chunk keys c/t/z/y/x)

    @property
    def chunk_grid(self) -> tuple[int, int, int]:
        return tuple(math.ceil(n / self.chunk) for n in self.shape)

    @property
    def unit_edge(self) -> int:
        """Voxels along an edge of one storage unit."""
        return self.chunk * (self.shard or 1)

    @property
    def unit_grid(self) -> tuple[int, int, int]:
        return tuple(math.ceil(n / self.unit_edge) for n in self.shape)

    def chunks_in_unit(self, unit: tuple[int, int, int]) -> tuple[int, int, int]:
        """Chunks of the unit that lie in the array (fewer at the far edges)."""
        k = self.shard or 1
        return tuple(min(k, self.chunk_grid[a] - unit[a] * k) for a in range(3))

    def valid_shape(self, chunk_index: tuple[int, int, int]) -> tuple[int, int, int]:
        return tuple(min(self.chunk, self.shape[a] - chunk_index[a] * self.chunk) for a in range(3))

    def unit_path(self, unit: tuple[int, int, int]) -> str:
        # Zarr v3 default chunk key encoding, separator "/": c/z/y/x
        return os.path.join(self._chunk_root(), *(str(int(i)) for i in unit))

    def _chunk_root(self) -> str:
        base = os.path.join(self.store, level_path(self.level), "c")
        return base if self.time is None else os.path.join(base, str(int(self.time)))

    def existing_units(self) -> set[tuple[int, int, int]]:
        """Units whose file exists (written whole by an earlier run)."""
        base = self._chunk_root()
        found: set[tuple[int, int, int]] = set()
        if not os.path.isdir(base):
            return found
        for z in os.scandir(base):
            if not (z.is_dir() and z.name.isdigit()):
                continue
            for y in os.scandir(z.path):
                if not (y.is_dir() and y.name.isdigit()):
                    continue
                for x in os.scandir(y.path):
                    if x.is_file() and x.name.isdigit():
                        found.add((int(z.name), int(y.name), int(x.name)))
        return found
