"""`npm run bench:convert`: the converter's throughput (MB/s of input) on
bonsai (256^3 float32, decoded from the shared rate-4 stream to a raw file)
and on a generated 1024^3 float32 volume (4 GiB, generated chunk by chunk;
generation is part of the time), with local threads (1 and 2) and a
2-process dask.distributed LocalCluster; next to zfpy compressing bonsai in
one call. Median of the repeats after the first (discarded); the 4 GiB runs
are single runs unless --big-repeats is given. Prints a table, writes JSON."""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import zfpy

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "converter"))

from zfpzarr import Options, convert  # noqa: E402

BONSAI = ROOT.parent / "shared" / "data" / "volumes" / "bonsai_256x256x256_float32.rate4.zfp"


def timed_runs(fn, repeats: int, discard_first: bool) -> tuple[list[float], float]:
    times = []
    for _ in range(repeats + (1 if discard_first else 0)):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    kept = times[1:] if discard_first else times
    return times, statistics.median(kept)


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--rate", type=float, default=4.0)
    p.add_argument("--repeats", type=int, default=3, help="kept repeats for bonsai (after one discarded)")
    p.add_argument("--big", default="1024x1024x1024", help="generated volume XxYxZ, or 'none'")
    p.add_argument("--big-repeats", type=int, default=1)
    p.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "convert.json"))
    args = p.parse_args()

    work = Path(tempfile.mkdtemp(prefix="bench-convert-"))
    rows = []
    try:
        bonsai = zfpy.decompress_numpy(BONSAI.read_bytes())
        raw = work / "bonsai_256x256x256_float32.raw"
        bonsai.tofile(raw)
        inputs = [("bonsai 256^3", str(raw), bonsai.nbytes, args.repeats, True)]
        if args.big != "none":
            x, y, z = (int(v) for v in args.big.split("x"))
            inputs.append((f"generated {args.big}", f"gen:{args.big}", x * y * z * 4, args.big_repeats,
                           args.big_repeats > 1))

        _, t = timed_runs(lambda: zfpy.compress_numpy(bonsai, rate=args.rate), args.repeats, True)
        rows.append({"input": "bonsai 256^3", "how": "zfpy.compress_numpy, one call (no levels, no store)",
                     "seconds": t, "mb_per_s": bonsai.nbytes / 1e6 / t})

        from distributed import Client, LocalCluster

        configs = [("local threads, 1", 1, None), ("local threads, 2", 2, None), ("LocalCluster, 2 processes", 2, "cluster")]
        for label, workers, kind in configs:
            client = cluster = None
            if kind == "cluster":
                cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
                client = Client(cluster)
            try:
                for name, spec, nbytes, repeats, discard in inputs:
                    out = work / "out.zarr"
                    summaries = []

                    def run():
                        shutil.rmtree(out, ignore_errors=True)
                        summaries.append(convert(spec, str(out), Options(rate=[args.rate]), client=client, workers=workers))

                    all_times, t = timed_runs(run, repeats, discard)
                    s = summaries[-1]
                    rows.append({"input": name, "how": label, "seconds": t, "mb_per_s": nbytes / 1e6 / t,
                                 "runs_s": all_times, "first_discarded": discard, "bytes_in": nbytes,
                                 "bytes_out": s.bytes_out, "levels": len(s.levels)})
                    shutil.rmtree(out, ignore_errors=True)
                    print(f"  {name:<24} {label:<28} {t:8.2f} s  {nbytes / 1e6 / t:8.1f} MB/s", flush=True)
            finally:
                if client:
                    client.close()
                    cluster.close()
    finally:
        shutil.rmtree(work, ignore_errors=True)

    print(f"\nconverter throughput, rate {args.rate:g}, chunk 64, levels auto ({os.cpu_count()} cores, "
          "shared machine: timings are noisy)")
    print(f"| {'input':<24} | {'how':<52} | {'median s':>9} | {'MB/s of input':>13} |")
    print(f"|{'-' * 26}|{'-' * 54}|{'-' * 11}|{'-' * 15}|")
    order = {name: i for i, (name, *_rest) in enumerate(inputs)}
    rows.sort(key=lambda r: order[r["input"]])  # stable: zfpy first, then the configurations
    for r in rows:
        print(f"| {r['input']:<24} | {r['how']:<52} | {r['seconds']:9.2f} | {r['mb_per_s']:13.1f} |")
    doc = {"benchmark": "convert", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version(),
                       "load_avg_after": os.getloadavg()},
           "rate": args.rate, "chunk": 64, "rows": rows,
           "note": "MB = 1e6 bytes of input; median of repeats after the first; generated volumes include generation time"}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(doc, indent=2) + "\n")
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
