"""Stores made from the shared volumes, checked against zfp (zfpy), a NumPy
reference of the levels, zarr-python reading them, and the OME-Zarr 0.5 schema."""
from __future__ import annotations

import json

import numpy as np
import pytest
import zarr
import zfpy

from conftest import read_raw, shared_volume, zfp_roundtrip
from zfpzarr import Options, convert


def reference_levels(volume: np.ndarray, count: int) -> list[np.ndarray]:
    """2x2x2 means, written independently of the converter: pad odd edges with
    NaN, average the 8 cells of each block, ignoring the NaN."""
    levels = [volume.astype(np.float32)]
    while len(levels) < count:
        v = levels[-1].astype(np.float64)
        pad = [(0, n % 2) for n in v.shape]
        v = np.pad(v, pad, constant_values=np.nan)
        z, y, x = (n // 2 for n in v.shape)
        cells = v.reshape(z, 2, y, 2, x, 2)
        levels.append(np.nanmean(cells, axis=(1, 3, 5)).astype(np.float32))
    return levels


def per_chunk_roundtrip(values: np.ndarray, chunk: int, rate: float) -> np.ndarray:
    out = np.empty_like(values)
    for idx in np.ndindex(*(-(-n // chunk) for n in values.shape)):
        sl = tuple(slice(i * chunk, (i + 1) * chunk) for i in idx)
        out[sl] = zfp_roundtrip(values[sl], rate)
    return out


def bonsai() -> np.ndarray:
    return zfpy.decompress_numpy(shared_volume("bonsai_256x256x256_float32.rate4.zfp").read_bytes())


CASES = {
    # name: (input path, loader of the same values, chunk, rate, shard)
    "bonsai-zfp": ("bonsai_256x256x256_float32.rate4.zfp", bonsai, 64, 4.0, None),
    "hydrogen-raw": ("hydrogen_atom_128x128x128_float32.raw",
                     lambda: read_raw(shared_volume("hydrogen_atom_128x128x128_float32.raw"), (128,) * 3, "<f4"), 32, 8.0, None),
    # 66^3: partial chunks and partial zfp blocks at the far edges; shards of 2^3 chunks, some cut by the edge
    "neghip-uint8-sharded": ("neghip_66x66x66_uint8.raw",
                             lambda: read_raw(shared_volume("neghip_66x66x66_uint8.raw"), (66,) * 3, "u1"), 32, 2.5, 2),
    "ironprot-uint8": ("ironProt_68x68x68_uint8.raw",
                       lambda: read_raw(shared_volume("ironProt_68x68x68_uint8.raw"), (68,) * 3, "u1"), 64, 3.0, None),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def converted(request, tmp_path_factory):
    name = request.param
    file, load, chunk, rate, shard = CASES[name]
    out = tmp_path_factory.mktemp(name) / "store.zarr"
    summary = convert(str(shared_volume(file)), str(out), Options(rate=[rate], chunk=chunk, shard=shard))
    return {"out": out, "values": load(), "chunk": chunk, "rate": rate, "shard": shard, "summary": summary}


def test_level0_chunks_equal_zfp_of_each_input_chunk(converted):
    arr = zarr.open_array(converted["out"] / "0", mode="r")
    values, c, rate = converted["values"], converted["chunk"], converted["rate"]
    assert arr.shape == values.shape and arr.dtype == np.float32
    grid = tuple(-(-n // c) for n in values.shape)
    for idx in np.ndindex(*grid):
        sl = tuple(slice(i * c, (i + 1) * c) for i in idx)
        np.testing.assert_array_equal(arr[sl], zfp_roundtrip(values[sl], rate), err_msg=f"chunk {idx}")


def test_level0_equals_the_whole_volume_as_one_stream(converted):
    arr = zarr.open_array(converted["out"] / "0", mode="r")
    whole = zfp_roundtrip(converted["values"], converted["rate"])
    assert arr[...].tobytes() == whole.tobytes()


def test_codec_metadata_is_numcodecs_zfpy_fixed_rate(converted):
    meta = json.loads((converted["out"] / "0" / "zarr.json").read_text())
    codecs = meta["codecs"]
    if converted["shard"]:
        assert codecs[0]["name"] == "sharding_indexed"
        assert codecs[0]["configuration"]["chunk_shape"] == [converted["chunk"]] * 3
        codecs = codecs[0]["configuration"]["codecs"]
    assert codecs == [{"name": "numcodecs.zfpy", "configuration": {"mode": 2, "rate": converted["rate"]}}]


def test_levels_equal_a_numpy_reference(converted):
    group = zarr.open_group(converted["out"], mode="r")
    count = len(group.attrs["ome"]["multiscales"][0]["datasets"])
    refs = reference_levels(converted["values"], count)
    assert max(refs[-1].shape) <= converted["chunk"] < max(refs[-2].shape)
    for level in range(1, count):
        stored = zarr.open_array(converted["out"] / str(level), mode="r")[...]
        expected = per_chunk_roundtrip(refs[level], converted["chunk"], converted["rate"])
        np.testing.assert_array_equal(stored, expected, err_msg=f"level {level}")


def test_chunk_ranges_are_min_max_of_decoded_chunks(converted):
    group = zarr.open_group(converted["out"], mode="r")
    c = converted["chunk"]
    for level in range(len(group.attrs["ome"]["multiscales"][0]["datasets"])):
        stored = zarr.open_array(converted["out"] / str(level), mode="r")[...]
        ranges = zarr.open_array(converted["out"] / "ranges" / str(level), mode="r")[...]
        grid = tuple(-(-n // c) for n in stored.shape)
        assert ranges.shape == (*grid, 2)
        for idx in np.ndindex(*grid):
            block = stored[tuple(slice(i * c, (i + 1) * c) for i in idx)]
            assert tuple(ranges[idx]) == (block.min(), block.max()), f"level {level} chunk {idx}"


def test_attributes_global_range_and_histogram(converted):
    attrs = zarr.open_group(converted["out"], mode="r").attrs["zfpzarr"]
    assert attrs["complete"] is True
    level0 = zarr.open_array(converted["out"] / "0", mode="r")[...]
    assert attrs["value_range"] == [float(level0.min()), float(level0.max())]
    h = attrs["histogram"]
    values = zarr.open_array(converted["out"] / str(h["level"]), mode="r")[...]
    counts, _ = np.histogram(values, bins=h["bins"], range=tuple(h["range"]))
    assert h["counts"] == counts.tolist() and sum(h["counts"]) == values.size


def test_every_chunk_file_is_a_zfp_stream_with_header(converted):
    if converted["shard"]:
        pytest.skip("sharded: chunks are inside shard files")
    c, rate = converted["chunk"], converted["rate"]
    for f in (converted["out"] / "0" / "c").rglob("*"):
        if f.is_file():
            h = zfpy.header(f.read_bytes())
            assert (h["nx"], h["ny"], h["nz"], h["mode"]) == (c, c, c, "rate")
            assert h["config"]["rate"] == rate
