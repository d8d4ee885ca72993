"""One chunk (or one shard of chunks) of a level: pad, encode, write, read back.

A chunk is encoded exactly as the array's codec (numcodecs.zfpy, fixed rate,
with header) encodes it: a zfp stream of the full chunk shape. Zarr pads a
chunk at the array's edge with the fill value; we pad it ourselves first,
the way zfp pads a partial 4x4x4 block inside a single stream, so that every
block that holds voxels of the volume encodes to exactly the bits it gets
when the whole volume is compressed as one stream. Voxels past that partial
block are zero. Readers never see either.

Chunk files are written whole and renamed into place, so a file that exists
is complete: a resumed run skips it (and decodes it for its value range).
"""
from __future__ import annotations

import os
import struct
import uuid

import numpy as np
import zfpy

from .layout import LevelLayout

_EMPTY = 0xFFFFFFFFFFFFFFFF


def _pad_axis(a: np.ndarray, axis: int, n: int) -> None:
    """zfp's pad_block along `axis`, for a partial last block of n % 4 values."""
    m = n % 4
    if m == 0 or n >= a.shape[axis]:
        return
    b = n - m

    def at(i: int):
        sl = [slice(None)] * 3
        sl[axis] = i
        return tuple(sl)

    if m == 1:
        a[at(b + 1)] = a[at(b)]
        a[at(b + 2)] = a[at(b + 1)]
        a[at(b + 3)] = a[at(b)]
    elif m == 2:
        a[at(b + 2)] = a[at(b + 1)]
        a[at(b + 3)] = a[at(b)]
    else:
        a[at(b + 3)] = a[at(b)]


def padded_chunk(values: np.ndarray, edge: int) -> np.ndarray:
    """The full (edge, edge, edge) float32 chunk for `values` (z, y, x), padded as zfp pads."""
    if values.shape == (edge, edge, edge):
        return np.ascontiguousarray(values, dtype=np.float32)
    out = np.zeros((edge, edge, edge), dtype=np.float32)
    nz, ny, nx = values.shape
    out[:nz, :ny, :nx] = values
    # zfp pads x within each row, then y, then z (gather_partial_float3)
    _pad_axis(out, 2, nx)
    _pad_axis(out, 1, ny)
    _pad_axis(out, 0, nz)
    return out


def encode_chunk(values: np.ndarray, edge: int, rate: float) -> bytes:
    return zfpy.compress_numpy(padded_chunk(values, edge), rate=rate, write_header=True)


def decode_chunk(data: bytes, valid: tuple[int, int, int]) -> np.ndarray:
    full = zfpy.decompress_numpy(data)
    return full[: valid[0], : valid[1], : valid[2]]


def value_range(decoded: np.ndarray) -> tuple[float, float]:
    return float(decoded.min()), float(decoded.max())


def _write_atomic(path: str, data: bytes) -> None:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = f"{path}.{uuid.uuid4().hex}.partial"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def _check_finite(values: np.ndarray, layout: LevelLayout, index) -> None:
    if not np.isfinite(values).all():
        raise ValueError(
            f"level {layout.level}, chunk {tuple(int(i) for i in index)} (z, y, x): the input has NaN or infinite values "
            "(after conversion to float32); zfp cannot encode them"
        )


def write_unit(block: np.ndarray, layout: LevelLayout, unit_index: tuple[int, int, int]) -> np.ndarray:
    """Encodes and writes one storage unit (a chunk, or a shard of chunks).

    Returns the [min, max] of the decoded values of each chunk of the unit
    that lies in the array, shape (kz, ky, kx, 2).
    """
    _check_finite(block, layout, unit_index)
    e = layout.chunk
    counts = layout.chunks_in_unit(unit_index)
    ranges = np.empty((*counts, 2), dtype=np.float32)
    pieces: list[bytes] = []
    for local in np.ndindex(*counts):
        sl = tuple(slice(local[a] * e, min((local[a] + 1) * e, block.shape[a])) for a in range(3))
        values = block[sl]
        data = encode_chunk(values, e, layout.rate)
        ranges[local] = value_range(decode_chunk(data, values.shape))
        pieces.append((local, data))
    if layout.shard is None:
        _write_atomic(layout.unit_path(unit_index), pieces[0][1])
    else:
        _write_atomic(layout.unit_path(unit_index), shard_bytes(pieces, layout.shard))
    return ranges


def unit_ranges(layout: LevelLayout, unit_index: tuple[int, int, int]) -> np.ndarray:
    """The chunk ranges of a unit already written (a resumed run), from its bytes."""
    counts = layout.chunks_in_unit(unit_index)
    with open(layout.unit_path(unit_index), "rb") as f:
        data = f.read()
    chunks = [data] if layout.shard is None else read_shard(data, layout.shard)
    ranges = np.empty((*counts, 2), dtype=np.float32)
    for local in np.ndindex(*counts):
        flat = 0 if layout.shard is None else int(np.ravel_multi_index(local, (layout.shard,) * 3))
        chunk_index = tuple(unit_index[a] * (layout.shard or 1) + local[a] for a in range(3))
        ranges[local] = value_range(decode_chunk(chunks[flat], layout.valid_shape(chunk_index)))
    return ranges


def _crc32c(data: bytes) -> int:
    import crc32c

    return crc32c.crc32c(data)


def shard_bytes(pieces: list, per_edge: int) -> bytes:
    """A Zarr v3 shard (sharding_indexed, index at the end: little-endian
    uint64 (offset, nbytes) per inner chunk in C order, then its crc32c).
    Inner chunks outside the array are absent (offset = nbytes = 2^64 - 1)."""
    n = per_edge**3
    index = np.full((n, 2), _EMPTY, dtype="<u8")
    out = bytearray()
    for local, data in pieces:
        flat = int(np.ravel_multi_index(local, (per_edge,) * 3))
        index[flat] = (len(out), len(data))
        out += data
    raw_index = index.tobytes()
    return bytes(out) + raw_index + struct.pack("<I", _crc32c(raw_index))


def read_shard(data: bytes, per_edge: int) -> list:
    n = per_edge**3
    size = n * 16 + 4
    if len(data) < size:
        raise ValueError("shard shorter than its index")
    raw_index = data[-size:-4]
    if struct.unpack("<I", data[-4:])[0] != _crc32c(raw_index):
        raise ValueError("shard index checksum mismatch")
    index = np.frombuffer(raw_index, dtype="<u8").reshape(n, 2)
    out = []
    for off, nbytes in index:
        out.append(None if off == _EMPTY else data[int(off) : int(off) + int(nbytes)])
    return out
