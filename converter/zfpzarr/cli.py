"""`python -m zfpzarr IN --out STORE.zarr [...]` (and `npm run convert -- ...`)."""
from __future__ import annotations

import argparse
import os
import sys

from .convert import Options, Summary, convert
from .inputs import InputError

EPILOG = """inputs:
  name_XxYxZ_dtype.raw         raw, shape and type from the name (or --dims, --dtype)
  file.nrrd                    NRRD, raw or gzip (voxel size from spacings / space directions)
  file.tif | folder | 'z*.tif' TIFF stack: one multi-page file (BigTIFF too) or many files
  file.h5:/path/to/dataset     HDF5 dataset
  file.nc:variable             NetCDF variable (xarray)
  store.zarr[:array]           an existing Zarr array (v2 or v3, any codec)
  file.zfp                     zfp fixed-rate stream (with header, or shape and rate in the name)
  gen:XxYxZ                    a generated float32 test volume
  'run/step_*.raw' --time      a time series: the files in name order (or a 4-D Zarr array: t, z, y, x)
scheduler:
  (none)                       local threads (--workers N threads)
  local                        a dask.distributed LocalCluster of --workers processes
  tcp://host:8786 | file.json  an existing dask.distributed scheduler (address or scheduler file)
"""


def _triple(text: str, sep: str, kind):
    parts = text.replace(",", sep).split(sep)
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(f"expected 3 values, got {text!r}")
    return tuple(kind(p) for p in parts)


def parse_args(argv):
    p = argparse.ArgumentParser(prog="zfpzarr", description=__doc__, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", help="the volume (see below)")
    p.add_argument("--out", required=True, help="the store to write (a folder, STORE.zarr)")
    p.add_argument("--rate", default=None, help="zfp fixed rate in bits per value; R0,R1,... per level, the last "
                   "repeated. Default: chosen from the data, the smallest whole rate whose RMS error on a sample of "
                   "the input's blocks is at most 0.15 of a step (integer inputs) or 1e-4 of the value range (float "
                   "inputs), used for every level (src/zfp/rate-choice.ts); zfp inputs: their own rate")
    p.add_argument("--chunk", type=int, default=64, help="chunk edge, a multiple of 4 (default 64)")
    p.add_argument("--levels", default="auto", help="number of levels, or auto (until the coarsest fits one chunk)")
    p.add_argument("--shard", type=int, default=None, help="Zarr v3 shards of N x N x N chunks")
    p.add_argument("--scheduler", default=None, help="dask.distributed scheduler address, scheduler file, or 'local'")
    p.add_argument("--workers", type=int, default=None, help="local threads (default: all cores), or processes with --scheduler local")
    p.add_argument("--memory-limit", default="auto", help="per worker process with --scheduler local (e.g. 2GB)")
    p.add_argument("--dims", type=lambda s: _triple(s, "x", int), help="raw input shape XxYxZ")
    p.add_argument("--dtype", choices=["uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64"])
    p.add_argument("--voxel-size", type=lambda s: _triple(s, ",", float), help="X,Y,Z (overrides the file's)")
    p.add_argument("--unit", help="unit of the voxel size, e.g. micrometer")
    p.add_argument("--overwrite", action="store_true", help="replace a store made from another input or with other settings")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--ranges-only", action="store_true",
                   help="INPUT is a store of lossless chunks: write only its per-brick value ranges at --rate (default 8) "
                        "to --out, for the page's &ranges=URL and the CLI's --ranges")
    p.add_argument("--time", nargs="?", const="series", default=None, metavar="T",
                   help="alone: INPUT is a time series, a pattern of files ('run/step_*.raw', one time point each, in "
                        "name order, all of one shape and type) or a Zarr array of 4 axes (t, z, y, x); the store gets "
                        "a t axis (chunks of one time point, ranges per time point). With --ranges-only: the time "
                        "point T (default 0)")
    p.add_argument("--time-step", type=float, default=1.0, help="with --time: the time between time points (OME scale along t, default 1)")
    p.add_argument("--time-unit", default=None, help="with --time: the unit of --time-step, e.g. second")
    p.add_argument("--channel", type=int, default=0, help="with --ranges-only: the channel (default 0)")
    a = p.parse_args(argv)
    try:
        rates = [float(r) for r in a.rate.split(",")] if a.rate else None
        levels = None if a.levels == "auto" else int(a.levels)
    except ValueError:
        p.error("--rate takes numbers, --levels a number or auto")
    series = a.time == "series"
    if a.ranges_only:
        if series:
            p.error("--ranges-only takes --time T, the time point whose ranges are written")
        try:
            a.time = int(a.time) if a.time is not None else 0
        except ValueError:
            p.error(f"--time {a.time}: a time point is a whole number")
    elif a.time is not None and not series:
        p.error(f"--time {a.time}: a time point is for --ranges-only; --time alone converts a time series")
    opts = Options(rate=rates, chunk=a.chunk, levels=levels, shard=a.shard, dims=a.dims, dtype=a.dtype,
                   voxel_size=a.voxel_size, unit=a.unit, overwrite=a.overwrite, time=series,
                   time_step=a.time_step, time_unit=a.time_unit)
    return a, opts


def connect(scheduler: str, workers: int | None, memory_limit: str):
    from distributed import Client, LocalCluster

    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1,
                               memory_limit=memory_limit, dashboard_address=None)
        return Client(cluster), cluster
    if os.path.isfile(scheduler):
        return Client(scheduler_file=scheduler), None
    return Client(scheduler), None


def format_summary(s: Summary) -> str:
    lines = [f"{s.out}: {'already complete, nothing to do' if s.state == 'complete' else 'complete'}"
             f"{' (resumed)' if s.state == 'resume' else ''}",
             *([f"  {s.time_points} time points (t axis)"] if s.time_points else []),
             f"  {'level':>5}  {'dims (x y z)':>18}  {'rate':>5}  {'chunks':>8}  {'files written':>13}  {'skipped':>8}"]
    for l in s.levels:
        dims = f"{l.shape[2]}x{l.shape[1]}x{l.shape[0]}"
        lines.append(f"  {l.level:>5}  {dims:>18}  {l.rate:>5g}  {l.chunks:>8}  {l.units_written:>13}  {l.units_skipped:>8}")
    if s.rate_choice is not None:
        lines.append(f"  {s.rate_choice.describe()}")
    lines.append(f"  value range {s.value_range[0]:g} .. {s.value_range[1]:g} (decoded)")
    lines.append(f"  in {s.bytes_in:,} B, out {s.bytes_out:,} B, ratio {s.ratio:.2f}, "
                 f"{s.seconds:.1f} s, {s.mb_per_s:.1f} MB/s of input")
    return "\n".join(lines)


def main(argv=None) -> int:
    args, opts = parse_args(sys.argv[1:] if argv is None else argv)
    if args.ranges_only:
        from .ranges_only import ranges_only

        if opts.rate is not None and len(opts.rate) != 1:
            print("error: --ranges-only takes one --rate", file=sys.stderr)
            return 2
        try:
            ranges_only(args.input, args.out, rate=opts.rate[0] if opts.rate else 8.0, time=args.time,
                        channel=args.channel, workers=args.workers, progress=not args.quiet)
            print(f"{args.out}: per-brick ranges of {args.input}")
            return 0
        except InputError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
    client = cluster = None
    try:
        if args.scheduler:
            client, cluster = connect(args.scheduler, args.workers, args.memory_limit)
            print(f"dask.distributed: {client.scheduler_info().get('address', args.scheduler)}, "
                  f"{len(client.scheduler_info().get('workers', {}))} workers", file=sys.stderr)
        summary = convert(args.input, args.out, opts, client=client, workers=args.workers, progress=not args.quiet)
        print(format_summary(summary))
        return 0
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"\ninterrupted: {args.out} is not complete; run the same command again to resume", file=sys.stderr)
        return 130
    except Exception as e:  # a failure inside a task (unreadable data, NaN, disk full): name the input
        print(f"error: {args.input}: {type(e).__name__}: {e}\n"
              f"{args.out} is not complete; fix the cause and run the same command again to resume", file=sys.stderr)
        return 1
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
