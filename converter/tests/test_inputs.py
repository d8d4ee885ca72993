"""Every input form gives the same level 0 as the raw volume it holds, with
the voxel size its format carries; bad inputs exit 1 with a message naming
the file and leave no store that claims to be complete."""
from __future__ import annotations

import gzip
import json

import h5py
import numpy as np
import pytest
import tifffile
import xarray as xr
import zarr
import zfpy

from conftest import run_cli, zfp_roundtrip
from zfpzarr import Options, convert
from zfpzarr.cli import main

X, Y, Z = 28, 24, 20
CHUNK, RATE = 16, 8.0


@pytest.fixture(scope="module")
def volume() -> np.ndarray:
    z, y, x = np.meshgrid(np.arange(Z), np.arange(Y), np.arange(X), indexing="ij")
    v = 1000 + 800 * np.sin(x / 5.0) * np.cos(y / 7.0) + 30 * z + (x * 7 + y * 13 + z * 17) % 11
    return v.astype(np.uint16)


def expected_level0(values: np.ndarray) -> np.ndarray:
    out = np.empty(values.shape, np.float32)
    for idx in np.ndindex(*(-(-n // CHUNK) for n in values.shape)):
        sl = tuple(slice(i * CHUNK, (i + 1) * CHUNK) for i in idx)
        out[sl] = zfp_roundtrip(values[sl], RATE)
    return out


def check(spec: str, tmp_path, values, voxel=None, unit=None, **opts):
    out = tmp_path / "out.zarr"
    convert(spec, str(out), Options(rate=[opts.pop("rate", RATE)], chunk=CHUNK, **opts))
    got = zarr.open_array(out / "0", mode="r")[...]
    np.testing.assert_array_equal(got, expected_level0(values))
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]
    assert attrs["zfpzarr"]["complete"] is True
    scale = attrs["ome"]["multiscales"][0]["datasets"][0]["coordinateTransformations"][0]["scale"]
    if voxel:
        np.testing.assert_allclose(scale, voxel[::-1], rtol=1e-6)
    if unit:
        assert attrs["ome"]["multiscales"][0]["axes"][0]["unit"] == unit
    return attrs


def test_raw_named_and_flags(tmp_path, volume):
    named = tmp_path / f"v_{X}x{Y}x{Z}_uint16.raw"
    volume.tofile(named)
    check(str(named), tmp_path, volume)
    plain = tmp_path / "plain.bin"
    volume.tofile(plain)
    check(str(plain), tmp_path / "b", volume, dims=(X, Y, Z), dtype="uint16")


def nrrd_header(extra: str, encoding: str) -> bytes:
    return (f"NRRD0004\n# made by the test\ntype: unsigned short\ndimension: 3\nsizes: {X} {Y} {Z}\n"
            f"endian: little\nencoding: {encoding}\n" + (f"{extra}\n" if extra else "") + "\n").encode()


def test_nrrd_raw_and_gzip(tmp_path, volume):
    raw = tmp_path / "v.nrrd"
    raw.write_bytes(nrrd_header("spacings: 0.5 0.25 2", "raw") + volume.tobytes())
    check(str(raw), tmp_path / "a", volume, voxel=(0.5, 0.25, 2.0))
    gz = tmp_path / "g.nrrd"
    gz.write_bytes(nrrd_header('space: left-posterior-superior\nspace directions: (0.3,0,0) (0,0.3,0) (0,0,1.2)\n'
                               'space units: "mm" "mm" "mm"', "gzip") + gzip.compress(volume.tobytes()))
    check(str(gz), tmp_path / "b", volume, voxel=(0.3, 0.3, 1.2), unit="millimeter")
    assert not (tmp_path / "b" / "out.zarr.input").exists(), "the inflated copy is removed at the end"


def test_tiff_multipage_multifile_and_bigtiff(tmp_path, volume):
    one = tmp_path / "stack.tif"
    tifffile.imwrite(one, volume, imagej=True, resolution=(1 / 0.2, 1 / 0.2), metadata={"spacing": 1.5, "unit": "um"})
    check(str(one), tmp_path / "a", volume, voxel=(0.2, 0.2, 1.5), unit="micrometer")
    folder = tmp_path / "planes"
    folder.mkdir()
    for z in range(Z):  # natural order: plane_2 before plane_10
        tifffile.imwrite(folder / f"plane_{z}.tif", volume[z])
    check(str(folder), tmp_path / "b", volume)
    check(str(folder / "plane_*.tif"), tmp_path / "c", volume)
    big = tmp_path / "big.tif"
    tifffile.imwrite(big, volume, bigtiff=True)
    check(str(big), tmp_path / "d", volume)


def test_hdf5_netcdf_zarr(tmp_path, volume):
    h5 = tmp_path / "v.h5"
    with h5py.File(h5, "w") as f:
        f.create_dataset("group/field", data=volume, chunks=(5, 8, 7), compression="gzip")
        f.create_dataset("small", data=np.zeros(4))
    check(f"{h5}:/group/field", tmp_path / "a", volume)
    nc = tmp_path / "v.nc"
    ds = xr.Dataset({"rho": (("z", "y", "x"), volume)},
                    coords={"x": ("x", np.arange(X) * 0.1, {"units": "m"}), "y": ("y", np.arange(Y) * 0.1, {"units": "m"}),
                            "z": ("z", np.arange(Z) * 0.4, {"units": "m"})})
    ds.to_netcdf(nc)
    check(f"{nc}:rho", tmp_path / "b", volume, voxel=(0.1, 0.1, 0.4), unit="meter")
    src = tmp_path / "in.zarr"
    arr = zarr.create_array(store=src, shape=volume.shape, chunks=(7, 9, 11), dtype="uint16", zarr_format=2)
    arr[...] = volume
    check(str(src), tmp_path / "c", volume)


def test_zfp_with_and_without_header(tmp_path, volume):
    f32 = volume.astype(np.float32)
    stream = zfpy.compress_numpy(f32, rate=6)
    with_header = tmp_path / "v.zfp"
    with_header.write_bytes(stream)
    decoded = zfpy.decompress_numpy(stream)
    attrs = check(str(with_header), tmp_path / "a", decoded, rate=RATE)
    headerless = tmp_path / f"v_{X}x{Y}x{Z}_float32.raw.crate6.zfp"
    headerless.write_bytes(zfpy.compress_numpy(f32, rate=6, write_header=False))
    check(str(headerless), tmp_path / "b", decoded)
    assert attrs["zfpzarr"]["params"]["rates"][0] == RATE


def test_generated_volume_is_the_same_in_any_chunking(tmp_path):
    a = tmp_path / "a.zarr"
    b = tmp_path / "b.zarr"
    convert("gen:40x36x20", str(a), Options(rate=[8], chunk=8))
    convert("gen:40x36x20", str(b), Options(rate=[8], chunk=32))
    va = zarr.open_array(a / "0")[...]
    vb = zarr.open_array(b / "0")[...]
    # different chunkings: same input values, each compressed per chunk; compare to the inputs' round trips
    from zfpzarr.inputs import open_input

    values = open_input("gen:40x36x20", 8, str(tmp_path)).array.compute()
    np.testing.assert_array_equal(open_input("gen:40x36x20", 32, str(tmp_path)).array.compute(), values)
    assert va.shape == vb.shape == (20, 36, 40)


def not_complete(out) -> bool:
    meta = out / "zarr.json"
    return not meta.exists() or json.loads(meta.read_text())["attributes"]["zfpzarr"]["complete"] is False


def bad_inputs(tmp_path, volume):
    cases = []
    p = tmp_path / f"short_{X}x{Y}x{Z}_uint16.raw"
    p.write_bytes(volume.tobytes()[:-2])
    cases.append((p, [], "the file has"))
    p = tmp_path / "noname.raw"
    p.write_bytes(b"\0" * 100)
    cases.append((p, [], "needs its shape and type"))
    p = tmp_path / "trunc.zfp"
    p.write_bytes(zfpy.compress_numpy(volume.astype(np.float32), rate=4)[:-100])
    cases.append((p, [], "truncated"))
    p = tmp_path / "prec.zfp"
    p.write_bytes(zfpy.compress_numpy(volume.astype(np.float32), precision=8))
    cases.append((p, [], "precision mode"))
    p = tmp_path / "d.zfp"
    p.write_bytes(zfpy.compress_numpy(volume.astype(np.float64), rate=4))
    cases.append((p, [], "float64"))
    p = tmp_path / "ascii.nrrd"
    p.write_bytes(nrrd_header("", "ascii") + b"1 2 3")
    cases.append((p, [], "encoding 'ascii'"))
    p = tmp_path / "cut.nrrd"
    p.write_bytes(nrrd_header("", "gzip") + gzip.compress(volume.tobytes())[:200])
    cases.append((p, [], "gzip data"))
    p = tmp_path / "c.h5"
    with h5py.File(p, "w") as f:
        f.create_dataset("c", data=np.zeros((4, 4, 4), np.complex64))
    cases.append((f"{p}:/c", [], "not supported"))
    cases.append((f"{p}:/nothere", [], "no dataset"))
    p = tmp_path / "fake.tif"
    p.write_bytes(b"II*\0garbage")
    cases.append((p, [], "not a readable TIFF"))
    cases.append((tmp_path / "missing_8x8x8_uint8.raw", [], "no such file"))
    p = tmp_path / f"ok_{X}x{Y}x{Z}_uint16.raw"
    volume.tofile(p)
    cases.append((p, ["--chunk", "30"], "multiple of 4"))
    p = tmp_path / f"nan_{X}x{Y}x{Z}_float32.raw"
    v = volume.astype(np.float32)
    v[3, 4, 5] = np.nan
    v.tofile(p)
    cases.append((p, [], "NaN"))
    return cases


class Result:
    def __init__(self, code, out, err):
        self.returncode, self.stdout, self.stderr = code, out, err


@pytest.fixture
def cli(capsys):
    """The command line in this process (what `python -m zfpzarr` runs; one
    test below runs the real process)."""
    def run(*args):
        capsys.readouterr()
        code = main([str(a) for a in args])
        captured = capsys.readouterr()
        return Result(code, captured.out, captured.err)
    return run


def test_a_bad_input_exits_1_from_the_real_process(tmp_path):
    r = run_cli(tmp_path / "nothing_4x4x4_uint8.raw", "--out", tmp_path / "o.zarr")
    assert r.returncode == 1 and "nothing_4x4x4_uint8.raw: no such file" in r.stderr
    assert not (tmp_path / "o.zarr").exists()


def test_bad_inputs_exit_1_naming_the_file(tmp_path, volume, cli):
    for i, (spec, flags, words) in enumerate(bad_inputs(tmp_path, volume)):
        out = tmp_path / f"bad{i}.zarr"
        r = cli(spec, "--out", out, "--quiet", *flags)
        assert r.returncode == 1, (spec, r.stdout, r.stderr)
        name = str(spec).split(":")[0].rsplit("/", 1)[-1] if "--chunk" not in flags else "--chunk"
        assert name in r.stderr and words in r.stderr, (spec, r.stderr)
        assert "Traceback" not in r.stderr
        assert not_complete(out), spec
    # and the next good file converts
    good = tmp_path / f"ok_{X}x{Y}x{Z}_uint16.raw"
    r = cli(good, "--out", tmp_path / "good.zarr", "--quiet", "--chunk", "16")
    assert r.returncode == 0, r.stderr
    assert not not_complete(tmp_path / "good.zarr")


def test_existing_paths_are_not_clobbered(tmp_path, volume, cli):
    good = tmp_path / f"ok_{X}x{Y}x{Z}_uint16.raw"
    volume.tofile(good)
    other = tmp_path / "notastore"
    other.mkdir()
    (other / "keep.txt").write_text("mine")
    r = cli(good, "--out", other, "--quiet")
    assert r.returncode == 1 and "not a store made by this converter" in r.stderr
    assert (other / "keep.txt").read_text() == "mine"
    out = tmp_path / "s.zarr"
    assert cli(good, "--out", out, "--quiet", "--rate", "4").returncode == 0
    r = cli(good, "--out", out, "--quiet", "--rate", "6")
    assert r.returncode == 1 and "other settings" in r.stderr
    r = cli(good, "--out", out, "--quiet", "--rate", "4")
    assert r.returncode == 0 and "already complete" in r.stdout
    assert cli(good, "--out", out, "--quiet", "--rate", "6", "--overwrite").returncode == 0


def test_levels_count_and_per_level_rates(tmp_path):
    out = tmp_path / "l.zarr"
    s = convert("gen:40x36x20", str(out), Options(rate=[8, 4], chunk=8, levels=2))
    assert [l.shape for l in s.levels] == [(20, 36, 40), (10, 18, 20)]
    meta = [json.loads((out / str(i) / "zarr.json").read_text()) for i in range(2)]
    assert [m["codecs"][0]["configuration"]["rate"] for m in meta] == [8, 4]
    deep = tmp_path / "d.zarr"
    s = convert("gen:40x36x20", str(deep), Options(rate=[8], chunk=8, levels=12))
    # halving stops at one voxel: 40 -> 20 -> 10 -> 5 -> 3 -> 2 -> 1
    assert [l.shape[2] for l in s.levels] == [40, 20, 10, 5, 3, 2, 1]
    auto = convert("gen:40x36x20", str(tmp_path / "a.zarr"), Options(rate=[8], chunk=8))
    assert [l.shape[2] for l in auto.levels] == [40, 20, 10, 5]
