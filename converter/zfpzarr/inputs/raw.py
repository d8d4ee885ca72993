"""Raw volumes (`name_XxYxZ_dtype.raw`, the page's naming rule, or flags) and NRRD (raw or gzip)."""
from __future__ import annotations

import gzip
import math
import os
import re
import zlib

import numpy as np

from .base import InputError, LazySource, Volume, check_volume, file_identity, lazy_array

# Same rule as src/core/naming.ts: _XxYxZ then an optional _dtype.
_SHAPE = re.compile(r"_(\d+)x(\d+)x(\d+)(?:_([a-z]+\d*))?", re.IGNORECASE)
_RATE = re.compile(r"\.c?rate(\d+(?:\.\d+)?)(?=\.|$)", re.IGNORECASE)
PAGE_DTYPES = ("uint8", "int8", "uint16", "int16", "float32", "float64")


def parse_name(path: str) -> dict:
    """dims (x, y, z), dtype and rate as the page reads them from a file name."""
    name = os.path.basename(path)
    out: dict = {}
    m = _SHAPE.search(name)
    if m:
        out["dims"] = (int(m.group(1)), int(m.group(2)), int(m.group(3)))
        t = (m.group(4) or "").lower()
        if t in PAGE_DTYPES:
            out["dtype"] = t
    r = _RATE.search(name)
    if r:
        out["rate"] = float(r.group(1))
    return out


class RawSource(LazySource):
    def __init__(self, path: str, offset: int, shape, dtype):
        self.path, self.offset, self.shape, self.dtype = path, offset, tuple(shape), np.dtype(dtype)

    def read(self, key):
        mm = np.memmap(self.path, dtype=self.dtype, mode="r", offset=self.offset, shape=self.shape)
        out = np.array(mm[key])
        del mm
        return out


def open_raw_file(path: str, shape_zyx, dtype, offset: int, chunk: int, what: str) -> RawSource:
    shape, dtype = check_volume(path, shape_zyx, dtype)
    need = offset + math.prod(shape) * dtype.itemsize
    size = os.path.getsize(path)
    if size < need:
        raise InputError(
            f"{path}: {what} {shape[2]}x{shape[1]}x{shape[0]} {dtype} needs {need} bytes, the file has {size}"
        )
    return RawSource(path, offset, shape, dtype)


def open_raw(path: str, chunk: int, dims=None, dtype=None, byte_order: str = "little") -> Volume:
    info = parse_name(path)
    dims = dims or info.get("dims")
    dtype = dtype or info.get("dtype")
    if not dims or not dtype:
        raise InputError(
            f"{path}: a raw file needs its shape and type, from the name (name_XxYxZ_dtype.raw) or --dims XxYxZ --dtype T"
        )
    dt = np.dtype(dtype).newbyteorder("<" if byte_order == "little" else ">")
    shape = (dims[2], dims[1], dims[0])
    nbytes = math.prod(shape) * dt.itemsize
    size = os.path.getsize(path)
    if size != nbytes:
        raise InputError(
            f"{path}: {dims[0]}x{dims[1]}x{dims[2]} {dtype} is {nbytes} bytes, the file has {size}; "
            "the name (or --dims/--dtype) must give the volume's shape and type"
        )
    src = open_raw_file(path, shape, dt, 0, chunk, "raw")
    return Volume(lazy_array(src, (chunk,) * 3, file_identity(path)), path, "raw")


_NRRD_TYPES = {
    "int8": ["signed char", "int8", "int8_t"],
    "uint8": ["uchar", "unsigned char", "uint8", "uint8_t"],
    "int16": ["short", "short int", "signed short", "signed short int", "int16", "int16_t"],
    "uint16": ["ushort", "unsigned short", "unsigned short int", "uint16", "uint16_t"],
    "int32": ["int", "signed int", "int32", "int32_t"],
    "uint32": ["uint", "unsigned int", "uint32", "uint32_t"],
    "int64": ["longlong", "long long", "long long int", "signed long long", "signed long long int", "int64", "int64_t"],
    "uint64": ["ulonglong", "unsigned long long", "unsigned long long int", "uint64", "uint64_t"],
    "float32": ["float"],
    "float64": ["double"],
}
_NRRD_TYPE = {alias: t for t, aliases in _NRRD_TYPES.items() for alias in aliases}
_UNITS = {"mm": "millimeter", "um": "micrometer", "µm": "micrometer", "micron": "micrometer", "nm": "nanometer",
          "cm": "centimeter", "m": "meter", "microns": "micrometer"}


def unit_name(u: str | None) -> str | None:
    if not u:
        return None
    u = u.strip().strip('"').strip()
    return _UNITS.get(u.lower(), u.lower()) if u else None


def _read_nrrd_header(path: str) -> tuple[dict, int]:
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    if not head.startswith(b"NRRD000"):
        raise InputError(f"{path}: not an NRRD file (no NRRD000x magic)")
    fields: dict = {}
    pos = 0
    lines = head.split(b"\n")
    for i, raw_line in enumerate(lines):
        if i == len(lines) - 1 and len(head) == (1 << 16):
            raise InputError(f"{path}: NRRD header longer than 64 KiB or without its blank line")
        pos += len(raw_line) + 1
        line = raw_line.decode("latin-1").rstrip("\r")
        if i == 0 or line.startswith("#"):
            continue
        if line == "":
            return fields, pos
        if ":=" in line:
            continue
        if ": " not in line:
            raise InputError(f"{path}: malformed NRRD header line {line!r}")
        k, v = line.split(": ", 1)
        fields[k.strip().lower()] = v.strip()
    return fields, len(head)  # header only (detached data)


def _nrrd_spacing(fields: dict) -> tuple[float, float, float] | None:
    if "spacings" in fields:
        try:
            s = [float(v) for v in fields["spacings"].split()]
        except ValueError:
            return None
        if len(s) == 3 and all(math.isfinite(v) and v > 0 for v in s):
            return (s[0], s[1], s[2])
    if "space directions" in fields:
        vecs = re.findall(r"\(([^)]*)\)", fields["space directions"])
        try:
            norms = [math.sqrt(sum(float(c) ** 2 for c in v.split(","))) for v in vecs]
        except ValueError:
            return None
        if len(norms) == 3 and all(n > 0 for n in norms):
            return (norms[0], norms[1], norms[2])
    return None


def open_nrrd(path: str, chunk: int, work_dir: str) -> Volume:
    fields, header_end = _read_nrrd_header(path)
    for need in ("type", "dimension", "sizes", "encoding"):
        if need not in fields:
            raise InputError(f"{path}: NRRD header has no '{need}' field")
    t = _NRRD_TYPE.get(fields["type"].lower())
    if t is None:
        raise InputError(f"{path}: NRRD type '{fields['type']}' is not supported")
    try:
        sizes = [int(v) for v in fields["sizes"].split()]
    except ValueError:
        raise InputError(f"{path}: NRRD sizes '{fields['sizes']}' are not integers") from None
    if fields["dimension"].strip() != "3" or len(sizes) != 3:
        raise InputError(f"{path}: NRRD dimension {fields['dimension']}; only 3D volumes are supported")
    dt = np.dtype(t)
    if dt.itemsize > 1:
        endian = fields.get("endian", "").lower()
        if endian not in ("little", "big"):
            raise InputError(f"{path}: NRRD of type {t} needs 'endian: little' or 'big'")
        dt = dt.newbyteorder("<" if endian == "little" else ">")
    encoding = fields["encoding"].lower()
    if encoding not in ("raw", "gzip", "gz"):
        raise InputError(f"{path}: NRRD encoding '{encoding}' is not supported (raw and gzip are)")
    data_path, offset = path, header_end
    data_file = fields.get("data file") or fields.get("datafile")
    if data_file:
        if data_file.startswith("LIST") or len(data_file.split()) > 1:
            raise InputError(f"{path}: NRRD with a list of data files is not supported")
        data_path = os.path.join(os.path.dirname(path), data_file)
        offset = 0
        if not os.path.isfile(data_path):
            raise InputError(f"{path}: its data file {data_path} does not exist")
    skip_text = fields.get("byte skip", "0")
    skip = int(skip_text) if skip_text.lstrip("-").isdigit() else -1
    if skip < 0:
        raise InputError(f"{path}: NRRD 'byte skip: {skip_text}' is not supported")
    shape = (sizes[2], sizes[1], sizes[0])
    check_volume(path, shape, dt)
    if encoding != "raw":
        data_path = _gunzip(path, data_path, offset, skip + math.prod(shape) * dt.itemsize, work_dir)
        offset = 0
    src = open_raw_file(data_path, shape, dt, offset + skip, chunk, "NRRD data of")
    vol = Volume(lazy_array(src, (chunk,) * 3, file_identity(path)), path, f"nrrd-{encoding}",
                 voxel_size=_nrrd_spacing(fields))
    units = (fields.get("space units") or fields.get("units") or "").replace('"', " ").split()
    if units and len(set(units)) == 1:
        vol.unit = unit_name(units[0])
    return vol


def _gunzip(path: str, data_path: str, offset: int, need: int, work_dir: str) -> str:
    """gzip data can only be read in order: it is inflated once, to a file
    next to the store (removed when the store is complete)."""
    os.makedirs(work_dir, exist_ok=True)
    out_path = os.path.join(work_dir, os.path.basename(path) + ".inflated")
    if os.path.exists(out_path) and os.path.getsize(out_path) == need:
        return out_path  # a resumed run
    written = 0
    tmp = out_path + ".partial"
    try:
        with open(data_path, "rb") as f, open(tmp, "wb") as out:
            f.seek(offset)
            gz = gzip.GzipFile(fileobj=f, mode="rb")
            while written < need:
                block = gz.read(min(16 << 20, need - written))
                if not block:
                    break
                out.write(block)
                written += len(block)
    except (OSError, EOFError, zlib.error) as e:
        raise InputError(f"{path}: the gzip data cannot be read ({e})") from None
    if written < need:
        os.remove(tmp)
        raise InputError(f"{path}: the gzip data holds {written} bytes, the header says {need}")
    os.replace(tmp, out_path)
    return out_path
