"""The zfp fixed rate chosen from the data, when none is given.

The shared definition is src/zfp/rate-choice.ts (the page, the CLI and the
benchmarks use it); this module implements exactly the same rule with zfpy,
so a store converted here gets the rate the page would choose for the same
volume:

- sample: the volume itself when it has at most CANDIDATE_BLOCKS (32768) 4x4x4 blocks;
  otherwise whole blocks on a regular sub-grid of the volume's complete
  blocks, at most CANDIDATE_BLOCKS of them (m per axis, the largest m with
  prod(min(full blocks on the axis, m)) <= CANDIDATE_BLOCKS; the k-th of n picks
  block floor((k + 1/2) * full / n)), put side by side into a small volume.
  An axis shorter than a block is taken whole. zfp encodes blocks
  independently, so each sampled block has exactly the error it has in the
  whole stream;
- measured blocks: the sample's complete blocks whose values are not all
  equal (structure); constant blocks (air around a scan, empty space) are
  exact at any rate and would dilute the error. They are put side by side
  along x (4k x 4 x 4 voxels), at most SAMPLE_BLOCKS of them (the j-th picks
  structured block floor((j + 1/2) * k / SAMPLE_BLOCKS)); a sample with no
  such block is measured whole;
- error: root mean square of decoded - source (float32 values) over the
  measured blocks' voxels;
- bound: integer sources: 0.15 of one source step; float sources: 1e-4 of the
  sample's value range (max - min, over every sampled block);
- rates: 1, 2, ..., 32 bits per value, bisected (the error falls as the rate
  grows); when 32 does not meet the bound, 32.

The converter has no stream budget, so there is no cap. The rate is chosen
from level 0 (the input) and used for every level of the store: the coarser
levels are 2x2x2 means of level 0, smoother and no harder to compress.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from decimal import ROUND_HALF_UP, Decimal
from typing import Callable, Sequence

import numpy as np
import zfpy

SAMPLE_BLOCKS = 4096  # structured blocks measured, at most (262,144 voxels)
CANDIDATE_BLOCKS = 32768  # blocks scanned for structure, at most; volumes of at most this many are their own sample
WHOLE_BLOCKS = 16384  # volumes of at most this many blocks are their own sample whatever the sub-grid's size
INTEGER_RMS_BOUND = 0.15  # integer sources: RMS error allowed, in source steps
FLOAT_RMS_BOUND = 1e-4  # float sources: RMS error allowed, as a fraction of the sample's value range
MIN_RATE = 1
MAX_RATE = 32


@dataclass
class SampleGrid:
    starts: tuple[list[int], list[int], list[int]]  # per axis (x, y, z): voxel starts of the sampled blocks
    dims: tuple[int, int, int]  # the sample's dimensions (x, y, z)
    whole: bool  # the sample is the whole volume
    blocks: int


def sample_grid(dims: Sequence[int], max_blocks: int = CANDIDATE_BLOCKS, whole_blocks: int = WHOLE_BLOCKS) -> SampleGrid:
    """The sample of a volume of `dims` (x, y, z): rate-choice.ts's sampleGrid."""
    dims = tuple(int(n) for n in dims)
    grid = [-(-n // 4) for n in dims]
    if grid[0] * grid[1] * grid[2] <= max(max_blocks, whole_blocks):
        starts = tuple([4 * i for i in range(g)] for g in grid)
        return SampleGrid(starts, dims, True, grid[0] * grid[1] * grid[2])
    full = [max(1, n // 4) for n in dims]
    m = 1
    while math.prod(min(f, m + 1) for f in full) <= max_blocks and any(f > m for f in full):
        m += 1
    starts = []
    for f in full:
        n = min(f, m)
        # Math.floor(((k + 0.5) * f) / n) in double precision, as the page computes it
        starts.append([4 * math.floor(((k + 0.5) * f) / n) for k in range(n)])
    sample_dims = tuple(dims[a] if dims[a] < 4 else 4 * len(starts[a]) for a in range(3))
    return SampleGrid(tuple(starts), sample_dims, False, len(starts[0]) * len(starts[1]) * len(starts[2]))


def sample_indices(grid: SampleGrid, dims: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per axis (x, y, z), the voxel indices the sample takes: a run of
    min(4, dim) voxels from each start."""
    out = []
    for a in range(3):
        run = min(4, int(dims[a]))
        out.append(np.array([s + i for s in grid.starts[a] for i in range(run)], dtype=np.int64))
    return tuple(out)


def gather_sample(array, grid: SampleGrid, compute: Callable | None = None) -> np.ndarray:
    """The sample (z, y, x) of a (z, y, x) dask or NumPy array, in its own
    type: the sampled blocks side by side, as rate-choice.ts's gatherSample
    places them. `compute` computes a list of dask arrays (default: dask's)."""
    dims = tuple(reversed(array.shape))
    if grid.whole:
        part = array
    else:
        xi, yi, zi = sample_indices(grid, dims)
        part = array[zi][:, yi][:, :, xi]
    if isinstance(part, np.ndarray):
        return part
    if compute is None:
        import dask

        (values,) = dask.compute(part)
    else:
        (values,) = compute([part])
    return np.asarray(values)


def is_integer_type(dtype) -> bool:
    return np.dtype(dtype).kind != "f"


def js_number(v: float) -> str:
    """JavaScript's String(v) for the values fmt() gives it (no exponent needed)."""
    return str(int(v)) if float(v).is_integer() else repr(float(v))


def fmt(v: float) -> str:
    """rate-choice.ts's fmt: 3 significant digits, exponent form below 0.01 or from 1000
    (JavaScript's toPrecision / toExponential rounding: the exact value, halves up)."""
    if v == 0:
        return "0"
    a = abs(v)
    d = Decimal(float(a))
    if a >= 1000 or a < 0.01:
        exp = d.adjusted()
        mant = (d.scaleb(-exp)).quantize(Decimal("0.01"), rounding=ROUND_HALF_UP)
        if mant >= 10:
            mant = (mant / 10).quantize(Decimal("0.01"), rounding=ROUND_HALF_UP)
            exp += 1
        text = f"{mant}e{'+' if exp >= 0 else '-'}{abs(exp)}"
    else:
        q = Decimal(1).scaleb(d.adjusted() - 2)
        text = js_number(float(d.quantize(q, rounding=ROUND_HALF_UP)))
    return ("-" if v < 0 else "") + text


def error_bound(dtype, sample32: np.ndarray) -> tuple[float, str]:
    """(largest RMS error allowed, how it was set) for a sample of `dtype` (its float32 values)."""
    name = np.dtype(dtype).name
    if is_integer_type(dtype):
        return INTEGER_RMS_BOUND, f"{js_number(INTEGER_RMS_BOUND)} of a source step ({name})"
    lo, hi = float(sample32.min()), float(sample32.max())
    return (FLOAT_RMS_BOUND * (hi - lo),
            f"{js_number(FLOAT_RMS_BOUND)} of the sampled value range {fmt(lo)} .. {fmt(hi)} ({name})")


def structured_blocks(sample32: np.ndarray, max_blocks: int = SAMPLE_BLOCKS) -> np.ndarray | None:
    """rate-choice.ts's structuredBlocks: the complete 4x4x4 blocks of a (z, y, x) sample whose
    values are not all equal, in raster order (x fastest), side by side along x; None when none is."""
    Z, Y, X = sample32.shape
    bz, by, bx = Z // 4, Y // 4, X // 4
    if bz * by * bx == 0:
        return None
    blocks = sample32[:4 * bz, :4 * by, :4 * bx].reshape(bz, 4, by, 4, bx, 4).transpose(0, 2, 4, 1, 3, 5).reshape(-1, 4, 4, 4)
    flat = blocks.reshape(len(blocks), 64)
    keep = (flat != flat[:, :1]).any(axis=1)
    if not keep.any():
        return None
    picked = blocks[keep]  # (k, z, y, x)
    k = min(len(picked), max_blocks)
    if k < len(picked):
        # Math.floor(((j + 0.5) * n) / k) in double precision, as the page computes it
        picked = picked[[math.floor(((j + 0.5) * len(picked)) / k) for j in range(k)]]
    return np.ascontiguousarray(picked.transpose(1, 2, 0, 3).reshape(4, 4, 4 * len(picked)))


def rate_error(sample32: np.ndarray, rate: float) -> dict:
    """{rate, rms, maxAbs} of zfp at `rate` on the sample (compressed as one stream)."""
    decoded = zfpy.decompress_numpy(zfpy.compress_numpy(sample32, rate=rate))
    e = np.abs(decoded - sample32)
    return {"rate": rate, "rms": float(np.sqrt(np.mean(e.astype(np.float64) ** 2))), "maxAbs": float(e.max())}


@dataclass
class RateChoice:
    rate: int
    how: str  # 'chosen': the smallest rate meeting the bound; 'unmet': none up to 32 does (32 is used)
    bound: float
    rule: str
    sample_rms: float
    sample_max: float
    sample_blocks: int  # blocks measured: the structured ones, or all sampled when none is
    candidate_blocks: int = 0  # blocks sampled
    structured: bool = False  # only the structured blocks were measured
    trials: list[dict] = field(default_factory=list)  # {rate, rms, maxAbs}, in the order tried
    ms: float = 0.0

    def record(self) -> dict:
        """rate-choice.ts's rateErrorRecord, without the time (so that a store's attributes
        are the same on every run); the store keeps it as `rateChoice`, with `rate`."""
        out = {"how": self.how, "bound": self.bound, "rule": self.rule, "sampleRms": self.sample_rms,
               "sampleMax": self.sample_max, "sampleBlocks": self.sample_blocks,
               "candidateBlocks": self.candidate_blocks, "structured": self.structured}
        if self.how == "chosen":
            out["faithfulRate"] = self.rate
        out["trials"] = [dict(t) for t in self.trials]
        return out

    def describe(self) -> str:
        """rate-choice.ts's describeRateChoice, e.g. "rate 10 chosen from the data: sampled RMS
        error 0.144 <= 0.15 (0.15 of a source step (int16)), 4096 sampled blocks, 6 rates tried in 41 ms"."""
        n = len(self.trials)
        blocks = (f"{self.sample_blocks} structured of {self.candidate_blocks} sampled blocks" if self.structured
                  else f"{self.sample_blocks} sampled blocks")
        sampled = f"{blocks}, {n} rate{'' if n == 1 else 's'} tried in {self.ms:.0f} ms"
        if self.how == "chosen":
            return (f"rate {self.rate} chosen from the data: sampled RMS error {fmt(self.sample_rms)} <= "
                    f"{fmt(self.bound)} ({self.rule}), {sampled}")
        return (f"rate {self.rate}: no rate meets {fmt(self.bound)} ({self.rule}); "
                f"sampled RMS error {fmt(self.sample_rms)}, {sampled}")


class NonFiniteSample(ValueError):
    """The sample holds NaN or infinite values (the conversion would fail on them too)."""


def choose_rate_of_sample(sample: np.ndarray, dtype, blocks: int) -> RateChoice:
    """The rule's search on a gathered sample (z, y, x) of a volume of `dtype`."""
    t0 = time.perf_counter()
    sample32 = np.ascontiguousarray(sample, dtype=np.float32)
    if not np.isfinite(sample32).all():
        raise NonFiniteSample("the input has NaN or infinite values (after conversion to float32); zfp cannot encode them")
    bound, rule = error_bound(dtype, sample32)
    structured = structured_blocks(sample32)
    measured = sample32 if structured is None else structured
    trials: list[dict] = []

    def trial(rate: int) -> dict:
        for t in trials:
            if t["rate"] == rate:
                return t
        t = rate_error(measured, rate)
        trials.append(t)
        return t

    lo, hi = MIN_RATE, MAX_RATE
    while lo < hi:
        mid = (lo + hi) // 2
        if trial(mid)["rms"] <= bound:
            hi = mid
        else:
            lo = mid + 1
    chosen = trial(hi)
    how = "unmet" if hi == MAX_RATE and not chosen["rms"] <= bound else "chosen"
    return RateChoice(rate=hi, how=how, bound=bound, rule=rule, sample_rms=chosen["rms"], sample_max=chosen["maxAbs"],
                      sample_blocks=blocks if structured is None else structured.shape[2] // 4, candidate_blocks=blocks,
                      structured=structured is not None, trials=trials, ms=(time.perf_counter() - t0) * 1000)


def choose_rate(array, compute: Callable | None = None) -> RateChoice:
    """The rate of a (z, y, x) volume (a dask or NumPy array in the input's own type)."""
    t0 = time.perf_counter()
    dims = tuple(int(n) for n in reversed(array.shape))
    grid = sample_grid(dims)
    sample = gather_sample(array, grid, compute)
    choice = choose_rate_of_sample(sample, array.dtype, grid.blocks)
    choice.ms = (time.perf_counter() - t0) * 1000
    return choice


def main(argv=None) -> int:
    """main([IN, --dims, XxYxZ, --dtype, T]): prints the choice for an input as JSON ({"rate",
    "rateError", "line"}), e.g. for checking it against rate-choice.ts:
    python -c 'import sys; from zfpzarr.rate import main; main(sys.argv[1:])' IN"""
    import argparse
    import json
    import tempfile

    from .inputs import open_input

    p = argparse.ArgumentParser(prog="zfpzarr.rate", description=main.__doc__)
    p.add_argument("input")
    p.add_argument("--dims", type=lambda s: tuple(int(n) for n in s.split("x")))
    p.add_argument("--dtype")
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as work:
        volume = open_input(a.input, 64, work, dims=a.dims, dtype=a.dtype)
        try:
            c = choose_rate(volume.array)
        finally:
            volume.close()
    print(json.dumps({"rate": c.rate, "rateError": {**c.record(), "ms": c.ms}, "line": c.describe()}))
    return 0
