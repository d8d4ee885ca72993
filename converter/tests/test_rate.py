"""Without --rate the converter chooses the rate from the data with the rule of
src/zfp/rate-choice.ts (zfpzarr/rate.py): the sample, the bound, the bisection,
and the store written at the chosen rate."""
from __future__ import annotations

import json

import dask.array as da
import numpy as np
import zarr

from conftest import read_raw, shared_volume, zfp_roundtrip
from zfpzarr import Options, convert
from zfpzarr.cli import format_summary
from zfpzarr.rate import (CANDIDATE_BLOCKS, FLOAT_RMS_BOUND, INTEGER_RMS_BOUND, choose_rate, fmt, gather_sample,
                          sample_grid)

NEGHIP = "neghip_66x66x66_uint8.raw"


def neghip() -> np.ndarray:
    return read_raw(shared_volume(NEGHIP), (66, 66, 66), "u1")


def rms_at(values: np.ndarray, rate: int) -> float:
    v = values.astype(np.float32)
    e = np.abs(zfp_roundtrip(v, rate) - v)
    return float(np.sqrt(np.mean(e.astype(np.float64) ** 2)))


def smallest_rate(values: np.ndarray, bound: float) -> int:
    """Linear scan: the smallest whole rate whose RMS error on `values` is at most `bound` (else 32)."""
    for r in range(1, 33):
        if rms_at(values, r) <= bound:
            return r
    return 32


def test_neghip_is_its_own_sample_and_chooses_rate_8():
    values = neghip()
    grid = sample_grid((66, 66, 66))
    # 17^3 = 4913 blocks <= WHOLE_BLOCKS: the whole volume (a 16^3 sub-grid would skip its central planes)
    assert grid.whole and grid.blocks == 17 ** 3 and grid.dims == (66, 66, 66)
    assert sample_grid((100, 100, 100)).whole  # 25^3 = 15625 blocks
    assert sample_grid((128, 128, 128)).whole  # 32^3 = 32768 blocks
    assert not sample_grid((256, 256, 256)).whole and sample_grid((256, 256, 256)).blocks == CANDIDATE_BLOCKS
    c = choose_rate(da.from_array(values, chunks=32))
    assert c.rate == 8 and c.how == "chosen"
    assert c.bound == INTEGER_RMS_BOUND and c.rule == "0.15 of a source step (uint8)"
    # the error is measured on the complete blocks that are not constant (the empty space around the molecule is exact)
    complete = [values[z:z + 4, y:y + 4, x:x + 4] for z in range(0, 64, 4) for y in range(0, 64, 4) for x in range(0, 64, 4)]
    structured = [b for b in complete if b.min() != b.max()]
    assert 0 < len(structured) < 16 ** 3
    assert c.structured and c.candidate_blocks == 17 ** 3 and c.sample_blocks == len(structured)
    side_by_side = np.concatenate(structured, axis=2)
    assert c.sample_rms == rms_at(side_by_side, 8) <= 0.15 < rms_at(side_by_side, 7)
    assert c.describe().startswith(f"rate 8 chosen from the data: sampled RMS error {fmt(c.sample_rms)} <= 0.15 "
                                   f"(0.15 of a source step (uint8)), {len(structured)} structured of 4913 sampled blocks, ")


def test_empty_space_around_the_content_does_not_lower_the_rate():
    # neghip inside a volume of zeros 4^3 times its size, at offsets that are not whole blocks: the sampled
    # blocks are mostly empty, and the rate is neghip's own
    values = neghip()
    padded = np.zeros((256, 256, 256), np.uint8)
    padded[101:167, 50:116, 23:89] = values
    c = choose_rate(da.from_array(padded, chunks=64))
    assert c.candidate_blocks == CANDIDATE_BLOCKS and 0 < c.sample_blocks < CANDIDATE_BLOCKS // 20
    assert c.rate == choose_rate(values).rate == 8


def test_the_sample_is_the_blocks_of_the_subgrid_side_by_side():
    # x: 12000 voxels (3000 complete blocks), y: 3 (shorter than a block: whole), z: 130 (32 complete, 2 voxels left)
    rng = np.random.default_rng(1)
    values = rng.integers(0, 60000, size=(130, 3, 12000), dtype=np.uint16)
    grid = sample_grid((12000, 3, 130))
    assert not grid.whole and grid.blocks <= CANDIDATE_BLOCKS
    full = (3000, 1, 32)
    m = max(k for k in range(1, 3001) if np.prod([min(f, k) for f in full]) <= CANDIDATE_BLOCKS)
    assert [len(s) for s in grid.starts] == [min(f, m) for f in full]
    expected = np.empty((4 * len(grid.starts[2]), 3, 4 * len(grid.starts[0])), np.uint16)
    for kz, z0 in enumerate(grid.starts[2]):
        for kx, x0 in enumerate(grid.starts[0]):
            expected[4 * kz:4 * kz + 4, :, 4 * kx:4 * kx + 4] = values[z0:z0 + 4, 0:3, x0:x0 + 4]
    got = gather_sample(da.from_array(values, chunks=(64, 3, 256)), grid)
    assert got.dtype == np.uint16
    np.testing.assert_array_equal(got, expected)
    for a, f in enumerate(full):
        n = len(grid.starts[a])
        assert grid.starts[a] == [4 * int(np.floor((k + 0.5) * f / n)) for k in range(n)]


def test_uint16_noise_chooses_the_smallest_rate_meeting_the_bound():
    rng = np.random.default_rng(7)
    values = rng.integers(0, 2**10, size=(32, 32, 32), dtype=np.uint16)
    assert sample_grid((32, 32, 32)).whole  # 512 blocks: the sample is the volume
    c = choose_rate(da.from_array(values, chunks=16))
    expected = smallest_rate(values, INTEGER_RMS_BOUND)
    assert 1 < expected < 32
    assert c.rate == expected and c.how == "chosen"
    assert c.sample_blocks == 512 and c.structured  # random values: every block has structure
    assert c.sample_rms == rms_at(values, expected)
    assert len(c.trials) <= 6 and {t["rate"] for t in c.trials} >= {16, expected}


def test_float32_bound_is_1e_4_of_the_sampled_range():
    z, y, x = np.meshgrid(np.arange(24), np.arange(20), np.arange(28), indexing="ij")
    values = (300.0 * np.sin(x / 4.0) * np.cos(y / 5.0) + 2.0 * z - 40.0).astype(np.float32)
    c = choose_rate(da.from_array(values, chunks=8))
    lo, hi = float(values.min()), float(values.max())
    assert c.bound == FLOAT_RMS_BOUND * (hi - lo)
    assert c.rule == f"0.0001 of the sampled value range {fmt(lo)} .. {fmt(hi)} (float32)"
    assert c.rate == smallest_rate(values, c.bound)
    assert c.sample_rms <= c.bound


def test_when_no_rate_meets_the_bound_32_is_used():
    # uint32 noise over the whole range: float32 itself is coarser than 0.15 of a step
    values = np.random.default_rng(3).integers(0, 2**32, size=(8, 8, 8), dtype=np.uint32)
    c = choose_rate(values)
    assert c.how == "unmet" and c.rate == 32 and c.sample_rms > c.bound == INTEGER_RMS_BOUND
    assert c.trials[-1]["rate"] == 32 and "faithfulRate" not in c.record()
    assert c.describe().startswith(f"rate 32: no rate meets 0.15 (0.15 of a source step (uint32)); "
                                   f"sampled RMS error {fmt(c.sample_rms)}, 8 structured of 8 sampled blocks, 6 rates tried in ")


def test_converting_without_rate_uses_the_chosen_rate_for_every_level(tmp_path):
    out = tmp_path / "n.zarr"
    s = convert(str(shared_volume(NEGHIP)), str(out), Options(chunk=32))
    assert s.rate_choice is not None and s.rate_choice.rate == 8
    count = len(s.levels)
    assert count == 3 and [l.rate for l in s.levels] == [8.0] * count
    for level in range(len(s.levels)):
        meta = json.loads((out / str(level) / "zarr.json").read_text())
        assert meta["codecs"] == [{"name": "numcodecs.zfpy", "configuration": {"mode": 2, "rate": 8.0}}]
    attrs = zarr.open_group(out, mode="r").attrs["zfpzarr"]
    assert attrs["params"]["rates"] == [8.0] * count
    assert [l["rate"] for l in attrs["levels"]] == [8.0] * count
    rc = attrs["rateChoice"]
    assert rc["rate"] == 8 and rc["how"] == "chosen" and rc["bound"] == 0.15 and rc["candidateBlocks"] == 17 ** 3
    assert rc["structured"] and 0 < rc["sampleBlocks"] < 17 ** 3
    assert rc["trials"][-1]["rate"] in (7, 8) and {t["rate"] for t in rc["trials"]} >= {7, 8}
    # level 0 is zfp at rate 8 of each input chunk
    values = neghip()
    stored = zarr.open_array(out / "0", mode="r")[...]
    np.testing.assert_array_equal(stored[:32, :32, :32], zfp_roundtrip(values[:32, :32, :32], 8))
    text = format_summary(s)
    assert f"\n  {s.rate_choice.describe()}\n" in text
    assert text.splitlines()[2].split()[2] == "8"  # level 0's rate column
    # the same command again: the same choice, so the same params: nothing to do
    again = convert(str(shared_volume(NEGHIP)), str(out), Options(chunk=32))
    assert again.state == "complete" and again.rate_choice.rate == 8


def test_a_given_rate_and_a_zfp_input_choose_nothing(tmp_path):
    s = convert(str(shared_volume(NEGHIP)), str(tmp_path / "g.zarr"), Options(rate=[3], chunk=32))
    assert s.rate_choice is None and {l.rate for l in s.levels} == {3.0}
    assert "rateChoice" not in zarr.open_group(tmp_path / "g.zarr", mode="r").attrs["zfpzarr"]
    assert "chosen from the data" not in format_summary(s)
    z = convert(str(shared_volume("bonsai_256x256x256_float32.rate4.zfp")), str(tmp_path / "z.zarr"),
                Options(chunk=64, levels=1))
    assert z.rate_choice is None and [l.rate for l in z.levels] == [4.0]
