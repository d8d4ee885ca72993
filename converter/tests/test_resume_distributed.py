"""A run killed half-way resumes to the same store; a dask.distributed
cluster of small workers writes the same bytes as local threads."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import CONVERTER, store_digests
from zfpzarr import Options, convert


def level0_files(out) -> int:
    base = out / "0" / "c"
    return sum(1 for _, _, files in os.walk(base) for f in files if f.isdigit()) if base.exists() else 0


def test_a_killed_run_resumes_to_the_same_store(tmp_path):
    spec, chunk = "gen:192x192x256", 16  # 2304 level-0 chunks
    reference = tmp_path / "ref.zarr"
    convert(spec, str(reference), Options(rate=[6], chunk=chunk))
    out = tmp_path / "killed.zarr"
    cmd = [sys.executable, "-m", "zfpzarr", spec, "--out", str(out), "--rate", "6", "--chunk", str(chunk), "--quiet"]
    env = {**os.environ, "PYTHONPATH": str(CONVERTER)}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while level0_files(out) < 300 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.01)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    written = level0_files(out)
    assert 300 <= written < 2304
    attrs = json.loads((out / "zarr.json").read_text())["attributes"]["zfpzarr"]
    assert attrs["complete"] is False
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "(resumed)" in r.stdout
    skipped = int(r.stdout.splitlines()[2].split()[-1])  # level 0's "skipped" column
    assert skipped >= written - 2  # the files being renamed at the kill may or may not have made it
    assert store_digests(out) == store_digests(reference)


# about 2 minutes on 2 cores
def test_distributed_small_workers_write_the_same_chunks_as_local_threads(tmp_path):
    from distributed import Client, LocalCluster

    spec = "gen:512x512x1024"  # float32: 1 GiB, generated chunk by chunk
    local = tmp_path / "local.zarr"
    convert(spec, str(local), Options(rate=[4]))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, memory_limit="256MB",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        before = set(client.scheduler_info()["workers"])
        dist = tmp_path / "dist.zarr"
        summary = convert(spec, str(dist), Options(rate=[4]), client=client)
        after = set(client.scheduler_info()["workers"])
        limits = {w["memory_limit"] for w in client.scheduler_info()["workers"].values()}
    assert summary.bytes_in == 1 << 30
    assert before == after, "a worker was restarted (out of memory?)"
    assert limits == {256_000_000}
    a, b = store_digests(local), store_digests(dist)
    assert len([k for k in a if "/c/" in k and k.startswith("0/")]) == 1024
    assert a == b
