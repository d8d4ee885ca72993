"""`--ranges-only`: per-brick ranges of a store of lossless chunks (the page's
bricks: the chunk when it is a cube of a multiple of 4, else 64^3), of the
values compressed at the rate and decoded. Checked against zfpy on the whole
level compressed as one stream (zfp codes every 4^3 block alone, so a brick's
decoded voxels are the whole stream's)."""
from __future__ import annotations

import numpy as np
import pytest
import zarr
import zfpy
from zarr.codecs import GzipCodec

from conftest import read_raw, shared_volume
from zfpzarr.cli import main
from zfpzarr.ranges_only import brick_edge


def brute(level: np.ndarray, edge: int, rate: float) -> np.ndarray:
    decoded = zfpy.decompress_numpy(zfpy.compress_numpy(np.ascontiguousarray(level, dtype=np.float32), rate=rate))
    grid = [-(-n // edge) for n in level.shape]
    out = np.zeros((*grid, 2), dtype=np.float32)
    for z in range(grid[0]):
        for y in range(grid[1]):
            for x in range(grid[2]):
                b = decoded[z * edge:(z + 1) * edge, y * edge:(y + 1) * edge, x * edge:(x + 1) * edge]
                out[z, y, x] = b.min(), b.max()
    return out


@pytest.mark.parametrize("chunks,edge", [((32, 32, 32), 32), ((20, 64, 64), 64), ((1, 66, 66), 64), ((100, 100, 100), 100)])
def test_ranges_equal_zfpy_over_the_whole_level(tmp_path, chunks, edge):
    a = read_raw(shared_volume("neghip_66x66x66_uint8.raw"), (66, 66, 66), "u1")
    src = tmp_path / "src.zarr"
    g = zarr.open_group(str(src), mode="w", zarr_format=2)
    g.create_array("0", shape=a.shape, chunks=chunks, dtype="uint8", compressors=None)[...] = a
    coarse = a[:66, :66, :66].reshape(33, 2, 33, 2, 33, 2).mean(axis=(1, 3, 5)).round().astype(np.uint8)
    g.create_array("1", shape=coarse.shape, chunks=chunks, dtype="uint8", compressors=None)[...] = coarse
    g.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": n, "type": "space"} for n in "zyx"],
                               "datasets": [{"path": "0"}, {"path": "1"}]}]
    assert brick_edge(chunks) == edge
    out = tmp_path / "ranges.zarr"
    assert main([str(src), "--out", str(out), "--ranges-only", "--rate", "6", "--quiet"]) == 0
    r = zarr.open_group(str(out), mode="r")
    info = r.attrs["zfpzarr_ranges"]
    assert info["rate"] == 6 and [l["brick"] for l in info["levels"]] == [edge, edge]
    for L, level in enumerate([a, coarse]):
        np.testing.assert_array_equal(r[f"ranges/{L}"][...], brute(level, edge, 6))


def test_a_5d_store_at_a_time_point_and_channel(tmp_path):
    rng = np.random.default_rng(3)
    a = (rng.random((2, 3, 12, 20, 24)) * 1000).astype(np.int16)
    src = tmp_path / "tc.zarr"
    g = zarr.open_group(str(src), mode="w", zarr_format=3)
    g.create_array("0", shape=a.shape, chunks=(1, 1, 4, 20, 24), dtype="int16", compressors=GzipCodec())[...] = a
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [{"name": n} for n in "tczyx"], "datasets": [{"path": "0"}]}]}
    out = tmp_path / "r.zarr"
    assert main([str(src), "--out", str(out), "--ranges-only", "--time", "1", "--channel", "2", "--quiet"]) == 0
    r = zarr.open_group(str(out), mode="r")
    assert r.attrs["zfpzarr_ranges"]["time"] == 1 and r.attrs["zfpzarr_ranges"]["channel"] == 2
    np.testing.assert_array_equal(r["ranges/0"][...], brute(a[1, 2], 64, 8))
    assert main([str(src), "--out", str(tmp_path / "bad.zarr"), "--ranges-only", "--time", "2", "--quiet"]) == 1


def test_brick_edge_nests_in_the_finer_level():
    # ngff-zarr's z-halved level 1 of a 96^3-chunked level 0: chunks (64, 96, 96) are no cube, 64^3 bricks
    # would not nest in level 0's 96^3 (the view's cut could not refine it): level 0's edge instead
    assert brick_edge((64, 96, 96)) == 64
    assert brick_edge((64, 96, 96), (2, 1, 1), (96, (1, 1, 1))) == 96
    # cubes of 64 at scale 2 over 96^3 bricks at scale (2, 1, 1): 128 is no multiple of 96 on y and x
    assert brick_edge((64, 64, 64), (2, 2, 2), (96, (2, 1, 1))) == 96
    # bricks that nest keep their own edge
    assert brick_edge((32, 32, 32), (2, 2, 2), (64, (1, 1, 1))) == 32
    assert brick_edge((64, 64, 64), (2, 2, 2), (64, (1, 1, 1))) == 64
