"""Shared helpers: the shared volumes, references made with zfpy, running the CLI."""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import zfpy

CONVERTER = Path(__file__).resolve().parents[1]
SHARED = CONVERTER.parents[1] / "shared" / "data"
VOLUMES = SHARED / "volumes"


def shared_volume(name: str) -> Path:
    path = VOLUMES / name
    if not path.exists():
        pytest.fail(f"shared data missing: {path} (CI clones ../shared beside the repository)")
    return path


def read_raw(path: Path, dims_xyz, dtype) -> np.ndarray:
    x, y, z = dims_xyz
    return np.fromfile(path, dtype=dtype).reshape(z, y, x)


def zfp_roundtrip(values: np.ndarray, rate: float) -> np.ndarray:
    """What zfp itself gives for `values` compressed alone at `rate` (the reference)."""
    return zfpy.decompress_numpy(zfpy.compress_numpy(np.ascontiguousarray(values, dtype=np.float32), rate=rate))


def run_cli(*args, timeout=600, env_extra=None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(CONVERTER)}
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "zfpzarr", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, env=env)


def store_digests(store: Path, under: str = "") -> dict[str, str]:
    """sha256 of every file of the store (or of one folder of it), by relative path."""
    out = {}
    base = store / under
    for root, _, files in os.walk(base):
        for f in files:
            p = Path(root) / f
            out[str(p.relative_to(store))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out
