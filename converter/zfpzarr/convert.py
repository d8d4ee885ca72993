"""From an input to a complete store, on Dask.

One graph for all levels: level 0 is the input as float32 in chunk-sized
blocks, each next level the 2x2x2 mean of the previous one (levels.py), and
per storage unit a task that pads, encodes, writes and decodes its chunks and
returns their value ranges (chunks.py). Units already on disk (an
interrupted run) become tasks that only decode their file, so their input is
never read. The ranges, the global range and the histogram are written
last, then the store is marked complete.
"""
from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass, field
from functools import partial

import dask
import dask.array as da
import numpy as np
import zarr
from dask.base import tokenize
from dask.highlevelgraph import HighLevelGraph

from .chunks import unit_ranges, write_unit
from .inputs import InputError, Series, Volume, open_input, open_series
from .layout import LevelLayout, level_path, level_shapes
from .levels import downsample
from .rate import NonFiniteSample, RateChoice, choose_rate
from .store import create_store, finish_store, histogram_level, ome_multiscales, plan_store, write_ranges

HISTOGRAM_BINS = 256


@dataclass
class Options:
    rate: list[float] | None = None  # per level, the last repeated; None: chosen from the data (zfp inputs: theirs)
    chunk: int = 64
    levels: int | None = None  # None: until the coarsest level fits one chunk
    shard: int | None = None  # chunks per shard edge
    dims: tuple[int, int, int] | None = None  # raw inputs without shape in the name (x, y, z)
    dtype: str | None = None
    voxel_size: tuple[float, float, float] | None = None  # x, y, z; overrides the input's
    unit: str | None = None
    overwrite: bool = False
    time: bool = False  # a time series: a pattern of files or a 4-D input (inputs/series.py)
    time_step: float = 1.0  # OME scale along t
    time_unit: str | None = None


@dataclass
class LevelSummary:
    level: int
    shape: tuple[int, int, int]  # z, y, x
    rate: float
    chunks: int
    units_written: int
    units_skipped: int


@dataclass
class Summary:
    out: str
    source: str
    state: str  # 'created', 'resumed' or 'complete' (nothing to do)
    levels: list[LevelSummary] = field(default_factory=list)
    bytes_in: int = 0
    bytes_out: int = 0
    seconds: float = 0.0
    value_range: tuple[float, float] | None = None
    rate_choice: RateChoice | None = None  # when the rate was chosen from the data
    time_points: int | None = None  # a time series: how many (levels' chunks and units count all of them)

    @property
    def ratio(self) -> float:
        return self.bytes_in / self.bytes_out if self.bytes_out else float("nan")

    @property
    def mb_per_s(self) -> float:
        return self.bytes_in / 1e6 / self.seconds if self.seconds > 0 else float("nan")


def check_options(opts: Options) -> None:
    if opts.chunk < 4 or opts.chunk % 4:
        raise InputError(f"--chunk {opts.chunk}: the chunk edge must be a positive multiple of 4")
    if opts.shard is not None and opts.shard < 1:
        raise InputError(f"--shard {opts.shard}: a shard holds N x N x N chunks, N >= 1")
    if opts.time and not (np.isfinite(opts.time_step) and opts.time_step > 0):
        raise InputError(f"--time-step {opts.time_step}: a positive number")
    if opts.levels is not None and opts.levels < 1:
        raise InputError(f"--levels {opts.levels}: at least 1")
    for r in opts.rate or []:
        bits = int(np.floor(64 * r + 0.5))
        if not (9 <= bits <= 64 * 32):
            raise InputError(f"--rate {r}: fixed rates from 0.140625 (9 bits per block) to 32 bits per value are supported")


def level_rates(opts: Options, volume: Volume, count: int, chosen: RateChoice | None = None) -> list[float]:
    """The given rates; else a zfp input's own rate; else the rate chosen from the data, for every level."""
    rates = list(opts.rate or [volume.default_rate or chosen.rate])
    return [float(rates[min(i, len(rates) - 1)]) for i in range(count)]


def choose_volume_rate(volume: Volume, client=None, workers: int | None = None) -> RateChoice:
    """The rate rate-choice.ts's rule chooses for the input (level 0), read from a sample of its blocks."""
    try:
        return choose_rate(volume.array, compute=lambda arrays: compute(arrays, client, workers))
    except NonFiniteSample as e:
        raise InputError(f"{volume.source}: {e}") from None


def unit_tasks(arr: da.Array, layout: LevelLayout, existing: set) -> da.Array:
    """A (chunk z, chunk y, chunk x, 2) float32 dask array of value ranges;
    computing it writes the level's missing units."""
    name = f"write-{tokenize(arr.name, layout)}"
    grid = layout.unit_grid
    dsk = {}
    for idx in np.ndindex(*grid):
        if idx in existing:
            dsk[(name, *idx, 0)] = (partial(unit_ranges, layout, idx),)
        else:
            dsk[(name, *idx, 0)] = (partial(write_unit, layout=layout, unit_index=idx), (arr.name, *idx))
    k = layout.shard or 1
    chunks = tuple(tuple(min(k, layout.chunk_grid[a] - i * k) for i in range(grid[a])) for a in range(3))
    graph = HighLevelGraph.from_collections(name, dsk, dependencies=[arr])
    return da.Array(graph, name, chunks=(*chunks, (2,)), dtype=np.float32, meta=np.empty((0,) * 4, np.float32))


def compute(arrays, client=None, workers: int | None = None, progress: bool = False):
    if client is not None:
        futures = client.compute(list(arrays))
        if progress:
            from distributed import progress as show

            show(futures)
            print()
        return client.gather(futures)
    if progress:
        from dask.diagnostics import ProgressBar

        with ProgressBar(dt=1.0):
            return dask.compute(*arrays, scheduler="threads", num_workers=workers)
    return dask.compute(*arrays, scheduler="threads", num_workers=workers)


def _level_tasks(source, layouts, opts, state: str):
    """Per level (each downsampled from the one before): its layout, the units already written
    (resuming), and the tasks that write the rest and return its chunk ranges."""
    level = source.astype(np.float32).rechunk((opts.chunk,) * 3)
    for layout in layouts:
        if layout.level > 0:
            level = downsample(level, opts.chunk)
        existing = layout.existing_units() if state == "resume" else set()
        write = level if not opts.shard or opts.shard == 1 else level.rechunk((layout.unit_edge,) * 3)
        yield layout, existing, unit_tasks(write, layout, existing)


def _remove_partial_files(out: str) -> None:
    """Files a killed run was writing (never renamed into place)."""
    for root, _, files in os.walk(out):
        for f in files:
            if f.endswith(".partial"):
                os.remove(os.path.join(root, f))


def _bytes_under(path: str) -> int:
    total = 0
    for root, _, files in os.walk(path):
        for f in files:
            total += os.path.getsize(os.path.join(root, f))
    return total


def convert(spec: str, out: str, opts: Options | None = None, client=None, workers: int | None = None,
            progress: bool = False, volume: Volume | None = None) -> Summary:
    """Converts `spec` (or an already opened `volume`) into the store `out`."""
    opts = opts or Options()
    check_options(opts)
    start = time.perf_counter()
    out = os.path.abspath(out)
    work_dir = out + ".input"
    if opts.time:
        series = open_series(spec, opts.chunk, work_dir, dims=opts.dims, dtype=opts.dtype)
        try:
            return _convert_series(series, out, opts, client, workers, progress, start, work_dir)
        finally:
            series.close()
    volume = volume or open_input(spec, opts.chunk, work_dir, dims=opts.dims, dtype=opts.dtype)
    try:
        return _convert(volume, out, opts, client, workers, progress, start, work_dir)
    finally:
        volume.close()


def _convert(volume: Volume, out, opts, client, workers, progress, start, work_dir) -> Summary:
    source = volume.array
    shapes = level_shapes(tuple(source.shape), opts.chunk, opts.levels)
    # Before the params: a resumed run must find the same rates (the sample is deterministic, so it does).
    choice = None if opts.rate or volume.default_rate else choose_volume_rate(volume, client, workers)
    rates = level_rates(opts, volume, len(shapes), choice)
    params = {
        "source": volume.source, "source_token": source.name, "shape": list(source.shape),
        "source_dtype": str(source.dtype), "chunk": opts.chunk, "shard": opts.shard,
        "levels": len(shapes), "rates": rates,
    }
    state = plan_store(out, params, opts.overwrite)
    summary = Summary(out=out, source=volume.source, state=state, bytes_in=int(source.nbytes), rate_choice=choice)
    voxel = tuple(opts.voxel_size or volume.voxel_size or (1.0, 1.0, 1.0))
    unit = opts.unit or volume.unit
    if state == "create":
        name = os.path.basename(volume.source.rstrip("/"))
        extra = {"voxel_size": list(voxel), "unit": unit, "axes": "zyx"}
        if choice is not None:
            extra["rateChoice"] = {"rate": choice.rate, **choice.record()}
        create_store(out, params, shapes, rates, opts.chunk, opts.shard,
                     ome_multiscales(name, shapes, voxel, unit), extra)
    layouts = [LevelLayout(out, i, shapes[i], opts.chunk, rates[i], opts.shard) for i in range(len(shapes))]
    if state != "complete":
        tasks = []
        for layout, existing, task in _level_tasks(source, layouts, opts, state):
            tasks.append(task)
            summary.levels.append(LevelSummary(layout.level, layout.shape, layout.rate,
                                               int(np.prod(layout.chunk_grid)),
                                               int(np.prod(layout.unit_grid)) - len(existing), len(existing)))
        ranges = compute(tasks, client, workers, progress)
        if state == "resume":
            _remove_partial_files(out)
        for layout, r in zip(layouts, ranges):
            write_ranges(out, layout.level, r)
        lo, hi = float(np.min(ranges[0][..., 0])), float(np.max(ranges[0][..., 1]))
        h_level = histogram_level(shapes)
        counts = _histogram(out, h_level, lo, hi, client, workers)
        finish_store(out, {
            "levels": [{"path": level_path(l.level), "shape": list(l.shape), "chunks": [opts.chunk] * 3,
                        "rate": l.rate, "ranges": f"ranges/{l.level}"} for l in layouts],
            "value_range": [lo, hi],
            "histogram": {"level": h_level, "range": [lo, hi], "bins": HISTOGRAM_BINS, "counts": counts},
        })
        shutil.rmtree(work_dir, ignore_errors=True)
    else:
        for layout in layouts:
            n = int(np.prod(layout.chunk_grid))
            summary.levels.append(LevelSummary(layout.level, layout.shape, layout.rate, n, 0, int(np.prod(layout.unit_grid))))
    attrs = zarr.open_group(store=out, mode="r").attrs["zfpzarr"]
    summary.value_range = tuple(attrs["value_range"])
    summary.bytes_out = _bytes_under(out)
    summary.seconds = time.perf_counter() - start
    return summary


def _histogram(out: str, level: int, lo: float, hi: float, client, workers) -> list[int]:
    """Histogram of the decoded values of `level` (the finest with at most 256^3 voxels)."""
    arr = da.from_zarr(zarr.open_array(store=out, path=level_path(level), mode="r"))
    top = hi if hi > lo else lo + 1.0
    counts, _ = da.histogram(arr, bins=HISTOGRAM_BINS, range=(lo, top))
    (result,) = compute([counts], client, workers)
    return [int(c) for c in result]


def _convert_series(series: Series, out, opts, client, workers, progress, start, work_dir) -> Summary:
    """A time series into one store with a t axis: each time point's levels
    are built and written as a single volume's are (the same graph), into
    chunks of one time point (c/t/z/y/x) and range arrays (T, cz, cy, cx, 2).
    The rate chosen from the data is chosen from time point 0 and used for
    every time point (one decode for the series)."""
    first = series.volumes[0]
    T = len(series.volumes)
    shapes = level_shapes(tuple(first.array.shape), opts.chunk, opts.levels)
    choice = None if opts.rate or first.default_rate else choose_volume_rate(first, client, workers)
    rates = level_rates(opts, first, len(shapes), choice)
    params = {
        "source": series.source, "files": series.files, "time_points": T,
        "source_tokens": [v.array.name for v in series.volumes], "shape": [T, *first.array.shape],
        "source_dtype": str(first.array.dtype), "chunk": opts.chunk, "shard": opts.shard,
        "levels": len(shapes), "rates": rates, "time_step": opts.time_step, "time_unit": opts.time_unit,
    }
    state = plan_store(out, params, opts.overwrite)
    summary = Summary(out=out, source=series.source, state=state,
                      bytes_in=int(sum(v.array.nbytes for v in series.volumes)), rate_choice=choice, time_points=T)
    voxel = tuple(opts.voxel_size or first.voxel_size or (1.0, 1.0, 1.0))
    unit = opts.unit or first.unit
    if state == "create":
        name = os.path.basename(series.source.rstrip("/"))
        extra = {"voxel_size": list(voxel), "unit": unit, "axes": "tzyx", "time_points": T}
        if choice is not None:
            extra["rateChoice"] = {"rate": choice.rate, **choice.record()}
        ome = ome_multiscales(name, shapes, voxel, unit, time={"step": opts.time_step, "unit": opts.time_unit})
        create_store(out, params, shapes, rates, opts.chunk, opts.shard, ome, extra, time_points=T)
    written = [0] * len(shapes)
    skipped = [0] * len(shapes)
    if state != "complete":
        value_ranges = []
        for t, volume in enumerate(series.volumes):
            layouts = [LevelLayout(out, i, shapes[i], opts.chunk, rates[i], opts.shard, time=t) for i in range(len(shapes))]
            tasks = []
            for layout, existing, task in _level_tasks(volume.array, layouts, opts, state):
                tasks.append(task)
                written[layout.level] += int(np.prod(layout.unit_grid)) - len(existing)
                skipped[layout.level] += len(existing)
            if progress:
                print(f"time point {t + 1} of {T}", flush=True)
            ranges = compute(tasks, client, workers, progress)
            for layout, r in zip(layouts, ranges):
                write_ranges(out, layout.level, r, time=t)
            value_ranges.append([float(np.min(ranges[0][..., 0])), float(np.max(ranges[0][..., 1]))])
        if state == "resume":
            _remove_partial_files(out)
        lo, hi = min(r[0] for r in value_ranges), max(r[1] for r in value_ranges)
        h_level = histogram_level(shapes)
        counts = _histogram(out, h_level, lo, hi, client, workers)
        finish_store(out, {
            "levels": [{"path": level_path(i), "shape": list(shapes[i]), "time_points": T, "chunks": [opts.chunk] * 3,
                        "rate": rates[i], "ranges": f"ranges/{i}"} for i in range(len(shapes))],
            "value_range": [lo, hi],
            "value_ranges": value_ranges,
            "histogram": {"level": h_level, "range": [lo, hi], "bins": HISTOGRAM_BINS, "counts": counts},
        })
        shutil.rmtree(work_dir, ignore_errors=True)
    else:
        skipped = [T * int(np.prod(LevelLayout(out, i, shapes[i], opts.chunk, rates[i], opts.shard).unit_grid))
                   for i in range(len(shapes))]
    for i, shape in enumerate(shapes):
        layout = LevelLayout(out, i, shape, opts.chunk, rates[i], opts.shard)
        summary.levels.append(LevelSummary(i, shape, rates[i], T * int(np.prod(layout.chunk_grid)), written[i], skipped[i]))
    attrs = zarr.open_group(store=out, mode="r").attrs["zfpzarr"]
    summary.value_range = tuple(attrs["value_range"])
    summary.bytes_out = _bytes_under(out)
    summary.seconds = time.perf_counter() - start
    return summary
