"""The group's attributes validate against the OME-Zarr 0.5 JSON schemas
(as published with the spec; taken from the ngff-zarr package's data files)."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import jsonschema
import pytest
import zarr
from referencing import Registry, Resource
from referencing.jsonschema import DRAFT202012

from conftest import shared_volume
from zfpzarr import Options, convert


def schemas() -> dict[str, dict]:
    spec = importlib.util.find_spec("ngff_zarr")  # located, not imported (installed without its dependencies)
    assert spec and spec.submodule_search_locations, "ngff-zarr (requirements-schemas.txt) is not installed"
    folder = Path(list(spec.submodule_search_locations)[0]) / "spec" / "0.5" / "schemas"
    return {p.name: json.loads(p.read_text()) for p in folder.glob("*.schema")}


def validator(name: str):
    all_schemas = schemas()
    registry = Registry().with_resources((s["$id"], Resource.from_contents(s, default_specification=DRAFT202012)) for s in all_schemas.values())
    schema = all_schemas[name]
    return jsonschema.Draft202012Validator(schema, registry=registry)


@pytest.mark.parametrize("voxel,unit", [(None, None), ((0.5, 0.5, 2.0), "micrometer")])
def test_attributes_validate_against_ome_zarr_05(tmp_path, voxel, unit):
    out = tmp_path / "s.zarr"
    convert(str(shared_volume("neghip_66x66x66_uint8.raw")), str(out),
            Options(rate=[4], chunk=16, voxel_size=voxel, unit=unit))
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]
    for name in ("image.schema", "strict_image.schema", "ome_zarr.schema"):
        errors = [e.message for e in validator(name).iter_errors(attrs)]
        assert errors == [], f"{name}: {errors}"
    ms = attrs["ome"]["multiscales"][0]
    assert [d["path"] for d in ms["datasets"]] == ["0", "1", "2", "3"]
    vz, vy, vx = (2.0, 0.5, 0.5) if voxel else (1.0, 1.0, 1.0)
    for level, d in enumerate(ms["datasets"]):
        scale, translation = d["coordinateTransformations"]
        f = 2**level
        assert scale == {"type": "scale", "scale": [vz * f, vy * f, vx * f]}
        assert translation == {"type": "translation", "translation": [v * (f - 1) / 2 for v in (vz, vy, vx)]}
        assert zarr.open_array(out / d["path"], mode="r").shape == tuple(-(-66 // f) for _ in range(3))
    if unit:
        assert all(a["unit"] == unit for a in ms["axes"])


def test_the_schema_rejects_broken_attributes(tmp_path):
    """The check can fail: the same attributes with a dataset missing its transformations are refused."""
    out = tmp_path / "s.zarr"
    convert(str(shared_volume("fuel_64x64x64_float32.raw")), str(out), Options(rate=[4], chunk=32))
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]
    assert list(validator("image.schema").iter_errors(attrs)) == []
    del attrs["ome"]["multiscales"][0]["datasets"][1]["coordinateTransformations"]
    assert list(validator("image.schema").iter_errors(attrs)) != []
