# PLY files as the tests read them with NumPy, apart from our own reader
# (src/mc/ply.ts): the binary little-endian meshes the exports write, float32
# x, y, z per vertex and per face a uchar count (3) and three int32 indices.
import numpy as np


def read_ply(path):
    """(vertices: nv x 3 float32, faces: nf x 3 int32) of a binary PLY file."""
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    head = data[:end].decode().split('\n')
    nv = int([line for line in head if line.startswith('element vertex')][0].split()[2])
    nf = int([line for line in head if line.startswith('element face')][0].split()[2])
    v = np.frombuffer(data, dtype='<f4', count=3 * nv, offset=end).reshape(nv, 3)
    f = np.frombuffer(data, dtype=np.dtype([('n', 'u1'), ('i', '<i4', 3)]), count=nf, offset=end + 12 * nv)
    assert (f['n'] == 3).all(), 'a face that is not a triangle'
    return v, f['i']
