"""zfp fixed-rate streams (with zfp's header, or header-less with shape and rate
in the name), decoded lazily: slabs of 4-voxel block rows are contiguous bits
of a fixed-rate stream, so a slab is realigned to a 64-bit word and decoded alone."""
from __future__ import annotations

import math
import os

import numpy as np
import zfpy

from .base import InputError, LazySource, Volume, check_volume, file_identity, lazy_array, slab_depth
from .raw import parse_name

MAGIC = b"zfp\x05"


class ZfpSource(LazySource):
    def __init__(self, path: str, shape, bits_per_block: int, payload_bit: int):
        self.path, self.shape, self.dtype = path, tuple(shape), np.dtype(np.float32)
        self.bits, self.payload_bit = bits_per_block, payload_bit
        nz, ny, nx = self.shape
        self.row_blocks = math.ceil(ny / 4) * math.ceil(nx / 4)

    def read(self, key):
        zs, ys, xs = key
        zb0, zb1 = zs.start // 4, math.ceil(zs.stop / 4)
        start = self.payload_bit + zb0 * self.row_blocks * self.bits
        end = self.payload_bit + zb1 * self.row_blocks * self.bits
        first_word = start // 64
        nwords = math.ceil(end / 64) - first_word + 1
        with open(self.path, "rb") as f:
            f.seek(first_word * 8)
            data = f.read(nwords * 8)
        data += b"\0" * (nwords * 8 - len(data))
        words = np.frombuffer(data, dtype="<u8")
        s = start % 64
        if s:
            words = (words[:-1] >> np.uint64(s)) | (words[1:] << np.uint64(64 - s))
        nz = min(self.shape[0], zb1 * 4) - zb0 * 4
        slab = zfpy._decompress(np.ascontiguousarray(words).view(np.uint8), zfpy.type_float,
                                [nz, self.shape[1], self.shape[2]], rate=self.bits / 64)
        return np.array(slab[zs.start - zb0 * 4 : zs.stop - zb0 * 4, ys, xs])


def open_zfp(path: str, chunk: int) -> Volume:
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(32)
    if head.startswith(MAGIC):
        try:
            h = zfpy.header(head)
        except Exception as e:  # zfpy raises plain exceptions for malformed headers
            raise InputError(f"{path}: unreadable zfp header ({e})") from None
        if h.get("mode") != "rate":
            raise InputError(f"{path}: zfp stream in {h.get('mode')} mode; only fixed-rate streams can be read in slabs "
                             "(decompress it and convert the raw volume)")
        if h["type"] is not np.float32:
            raise InputError(f"{path}: zfp stream of {np.dtype(h['type'])}; only float32 streams are supported")
        if h["nz"] == 0 or h["ny"] == 0:
            raise InputError(f"{path}: zfp stream of {1 + (h['ny'] > 0)} dimensions; a volume has 3")
        bits = int(h["config"]["expert"]["maxbits"])
        header_bits = 96 if bits <= 2048 else 148
        dims = (h["nx"], h["ny"], h["nz"])
    else:
        info = parse_name(path)
        if "dims" not in info or "rate" not in info:
            raise InputError(f"{path}: no zfp header; a header-less stream needs its shape and rate in the name "
                             "(name_XxYxZ_float32.raw.crateR.zfp)")
        dims = info["dims"]
        bits = int(math.floor(64 * info["rate"] + 0.5))
        header_bits = 0
    shape, _ = check_volume(path, (dims[2], dims[1], dims[0]), np.float32)
    blocks = math.ceil(dims[0] / 4) * math.ceil(dims[1] / 4) * math.ceil(dims[2] / 4)
    need = math.ceil((header_bits + blocks * bits) / 64) * 8
    if size < need:
        raise InputError(f"{path}: zfp stream of {dims[0]}x{dims[1]}x{dims[2]} at {bits} bits per block needs "
                         f"{need} bytes, the file has {size} (truncated?)")
    if header_bits == 0 and size != need:
        raise InputError(f"{path}: a header-less stream of this shape and rate is {need} bytes, the file has {size}")
    src = ZfpSource(path, shape, bits, header_bits)
    depth = slab_depth(chunk, shape[1] * shape[2] * 4)
    arr = lazy_array(src, (depth, shape[1], shape[2]), file_identity(path))
    return Volume(arr, path, "zfp", default_rate=bits / 64)
