"""Time series (`--time`, issue 47): files matched by a pattern (in name order)
or a 4-D Zarr array into one store with a t axis, checked per time point
against zfp (zfpy), the NumPy reference of the levels (test_roundtrip.py),
zarr-python reading the store, and the OME-Zarr 0.5 schemas."""
from __future__ import annotations

import json

import numpy as np
import pytest
import zarr

from conftest import read_raw, run_cli, shared_volume, store_digests, zfp_roundtrip
from test_roundtrip import per_chunk_roundtrip, reference_levels
from test_schema import validator
from zfpzarr import Options, convert

RATE = 4.0
CHUNK = 32  # 66^3: partial chunks and partial zfp blocks at the far edges; 3 levels (66, 33, 17)


def series_values() -> list[np.ndarray]:
    """Three time points made from neghip (uint8, 66^3): as it is, shifted along x, inverted."""
    v = read_raw(shared_volume("neghip_66x66x66_uint8.raw"), (66,) * 3, "u1")
    return [v, np.roll(v, 5, axis=2), (255 - v).astype(np.uint8)]


@pytest.fixture(scope="module", params=[None, 2], ids=["unsharded", "sharded"])
def series(request, tmp_path_factory):
    work = tmp_path_factory.mktemp("series")
    values = series_values()
    # names whose order is the time order; a file that is no time point is not matched
    for t, v in enumerate(values):
        v.tofile(work / f"step_{'abc'[t]}_66x66x66_uint8.raw")
    (work / "notes.txt").write_text("not a time point")
    out = work / "s.zarr"
    summary = convert(str(work / "step_*.raw"), str(out),
                      Options(rate=[RATE], chunk=CHUNK, shard=request.param, time=True, time_step=0.5, time_unit="second"))
    return {"work": work, "out": out, "values": values, "shard": request.param, "summary": summary}


def test_level0_of_each_time_point_is_the_whole_volume_as_one_stream(series):
    arr = zarr.open_array(series["out"] / "0", mode="r")
    assert arr.shape == (3, 66, 66, 66) and arr.chunks == (1, CHUNK, CHUNK, CHUNK)
    for t, v in enumerate(series["values"]):
        assert arr[t].tobytes() == zfp_roundtrip(v, RATE).tobytes(), f"time point {t}"


def test_levels_of_each_time_point_equal_a_numpy_reference(series):
    for t, v in enumerate(series["values"]):
        refs = reference_levels(v, 3)
        for level in (1, 2):
            stored = zarr.open_array(series["out"] / str(level), mode="r")
            assert stored.shape == (3, *refs[level].shape)
            np.testing.assert_array_equal(stored[t], per_chunk_roundtrip(refs[level], CHUNK, RATE),
                                          err_msg=f"time point {t} level {level}")


def test_ranges_per_time_point_are_min_max_of_decoded_chunks(series):
    for level in range(3):
        stored = zarr.open_array(series["out"] / str(level), mode="r")[...]
        ranges = zarr.open_array(series["out"] / "ranges" / str(level), mode="r")[...]
        grid = tuple(-(-n // CHUNK) for n in stored.shape[1:])
        assert ranges.shape == (3, *grid, 2)
        for t in range(3):
            for idx in np.ndindex(*grid):
                block = stored[(t, *(slice(i * CHUNK, (i + 1) * CHUNK) for i in idx))]
                assert tuple(ranges[(t, *idx)]) == (block.min(), block.max()), f"time point {t} level {level} chunk {idx}"


def test_attributes_value_ranges_and_histogram(series):
    attrs = zarr.open_group(series["out"], mode="r").attrs["zfpzarr"]
    assert attrs["complete"] is True and attrs["axes"] == "tzyx" and attrs["time_points"] == 3
    level0 = zarr.open_array(series["out"] / "0", mode="r")[...]
    assert attrs["value_ranges"] == [[float(level0[t].min()), float(level0[t].max())] for t in range(3)]
    assert attrs["value_range"] == [float(level0.min()), float(level0.max())]
    h = attrs["histogram"]
    values = zarr.open_array(series["out"] / str(h["level"]), mode="r")[...]
    counts, _ = np.histogram(values, bins=h["bins"], range=tuple(h["range"]))
    assert h["counts"] == counts.tolist() and sum(h["counts"]) == values.size


def test_ome_axes_t_z_y_x_validate_against_ome_zarr_05(series):
    attrs = json.loads((series["out"] / "zarr.json").read_text())["attributes"]
    for name in ("image.schema", "strict_image.schema", "ome_zarr.schema"):
        errors = [e.message for e in validator(name).iter_errors(attrs)]
        assert errors == [], f"{name}: {errors}"
    ms = attrs["ome"]["multiscales"][0]
    assert [a["name"] for a in ms["axes"]] == ["t", "z", "y", "x"]
    assert ms["axes"][0] == {"name": "t", "type": "time", "unit": "second"}
    for level, d in enumerate(ms["datasets"]):
        scale, translation = d["coordinateTransformations"]
        f = 2**level
        assert scale["scale"] == [0.5, f, f, f]
        assert translation["translation"] == [0.0, *((f - 1) / 2,) * 3]


def test_a_4d_zarr_array_gives_the_same_store(series, tmp_path):
    src = tmp_path / "in.zarr"
    arr = zarr.create_array(src, shape=(3, 66, 66, 66), chunks=(2, 33, 33, 33), dtype="uint8")
    arr[...] = np.stack(series["values"])
    out = tmp_path / "s.zarr"
    convert(str(src), str(out), Options(rate=[RATE], chunk=CHUNK, shard=series["shard"], time=True, time_step=0.5,
                                        time_unit="second"))
    for under in ("0", "1", "2", "ranges"):
        assert store_digests(out, under) == store_digests(series["out"], under), under


def test_a_rerun_finds_the_store_complete(series):
    again = convert(str(series["work"] / "step_*.raw"), str(series["out"]),
                    Options(rate=[RATE], chunk=CHUNK, shard=series["shard"], time=True, time_step=0.5, time_unit="second"))
    assert again.state == "complete" and again.time_points == 3


def test_refusals_name_the_file_and_both_shapes(tmp_path):
    v = read_raw(shared_volume("neghip_66x66x66_uint8.raw"), (66,) * 3, "u1")
    v.tofile(tmp_path / "a_66x66x66_uint8.raw")
    v[:, :, :64].copy().tofile(tmp_path / "b_64x66x66_uint8.raw")
    r = run_cli(tmp_path / "*.raw", "--time", "--out", tmp_path / "s.zarr", "--quiet", "--rate", "4")
    assert r.returncode == 1
    assert f"{tmp_path / 'b_64x66x66_uint8.raw'}: 64x66x66 uint8, but {tmp_path / 'a_66x66x66_uint8.raw'} (time point 0) is 66x66x66 uint8" in r.stderr
    assert not (tmp_path / "s.zarr").exists()
    r = run_cli(tmp_path / "nothing_*.raw", "--time", "--out", tmp_path / "s.zarr", "--quiet")
    assert r.returncode == 1 and "no files match the pattern" in r.stderr
    r = run_cli(tmp_path / "a_66x66x66_uint8.raw", "--time", "--out", tmp_path / "s.zarr", "--quiet")
    assert r.returncode == 1 and "with --time, give a pattern of files" in r.stderr
    flat = tmp_path / "flat.zarr"
    zarr.create_array(flat, shape=(66, 66, 66), chunks=(33, 33, 33), dtype="uint8")
    r = run_cli(flat, "--time", "--out", tmp_path / "s.zarr", "--quiet")
    assert r.returncode == 1 and "a time series in one array has 4 axes (t, z, y, x)" in r.stderr
    r = run_cli(tmp_path / "a_66x66x66_uint8.raw", "--time", "3", "--out", tmp_path / "s.zarr", "--quiet")
    assert r.returncode == 2 and "a time point is for --ranges-only" in r.stderr
