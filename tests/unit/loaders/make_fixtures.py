"""Writes extra LAS/LAZ and TIFF test files with laspy/lazrs and tifffile, and
the values those independent readers decode from them, for the loader tests.

    python make_fixtures.py OUT_DIR      -> OUT_DIR/*.las|laz|tif and OUT_DIR/expected.json

The shared data covers LAS 1.2 and plain/LZW TIFF; this adds what it lacks:
LAS 1.4 point formats 6/7/8 (RGB, NIR, extended classification), and TIFF
variants (deflate, JPEG, PackBits, predictors, tiles, planar, big-endian,
BigTIFF, all sample types), a stack of single-page files, and unsupported files.
Expected values always come from reading the written file back with the
reference reader, never from the arrays we wrote.
"""
import hashlib
import json
import os
import sys

import laspy
import numpy as np
import tifffile


def sha(a):
    return hashlib.sha256(np.ascontiguousarray(a).astype(a.dtype.newbyteorder('<')).tobytes()).hexdigest()


def pyxs(arr, axes):
    """Re-lays tifffile's array out as [page][y][x][sample]."""
    a = arr
    if 'S' in axes and axes.index('S') < axes.index('Y'):  # planar: S before Y
        a = np.moveaxis(a, axes.index('S'), -1)
    return a


def tiff_entry(path, extra=None):
    with tifffile.TiffFile(path) as tf:
        page = tf.pages[0]
        series = tf.series[0]
        arr = series.asarray()
        e = {
            'pages': len(tf.pages),
            'width': page.imagewidth,
            'height': page.imagelength,
            'bits_per_sample': page.bitspersample,
            'samples_per_pixel': page.samplesperpixel,
            'sample_format': int(page.sampleformat),
            'compression': int(page.compression),
            'planar_config': int(page.planarconfig),
            'tiled': page.is_tiled,
            'dtype': str(arr.dtype.name),
            'shape': list(arr.shape),
            'axes': series.axes,
            'sha256_pyxs': sha(pyxs(arr, series.axes)),
            'min': float(arr.min()),
            'max': float(arr.max()),
            'mean': float(arr.astype(np.float64).mean()),
        }
    if extra:
        e.update(extra)
        if extra.get('lossy'):
            # Lossy files: the decoded samples, to compare value by value.
            pyxs(arr, series.axes).astype(arr.dtype.newbyteorder('<')).tofile(path + '.decoded.raw')
    return e


def make_tiffs(out):
    rng = np.random.default_rng(7)
    files = {}

    def field(shape, dtype):
        # Smooth data with noise: compresses, and predictors matter.
        z = np.indices(shape[:3] if len(shape) >= 3 else shape).sum(0).astype(np.float64)
        base = np.sin(z / 9.0) * 0.5 + 0.5
        if len(shape) > len(base.shape):
            base = np.repeat(base[..., None], shape[-1], axis=-1)
        noise = rng.random(shape)
        v = base * 0.8 + noise * 0.2
        if np.issubdtype(dtype, np.floating):
            return (v * 1000 - 300).astype(dtype)
        info = np.iinfo(dtype)
        lo, hi = max(info.min, -30000), min(info.max, 60000)
        return (lo + v * (hi - lo)).astype(dtype)

    variants = [
        # name, shape (pages, y, x[, s]), dtype, kwargs
        ('u8_deflate.tif', (3, 37, 53), np.uint8, dict(compression='adobe_deflate')),
        ('u16_lzw_pred_be.tif', (4, 40, 33), np.uint16, dict(compression='lzw', predictor=True, byteorder='>')),
        ('f32_deflate_fpred_tiled.tif', (2, 70, 45), np.float32, dict(compression='zlib', predictor=3, tile=(32, 32))),
        ('i16_packbits.tif', (3, 25, 31), np.int16, dict(compression='packbits')),
        ('f64_none.tif', (2, 19, 23), np.float64, dict()),
        ('u32_deflate.tif', (2, 21, 17), np.uint32, dict(compression='zlib')),
        ('i32_lzw.tif', (2, 21, 17), np.int32, dict(compression='lzw')),
        ('i8_none_tiled.tif', (2, 50, 40), np.int8, dict(tile=(16, 16))),
        ('rgb_planar_lzw.tif', (2, 30, 41, 3), np.uint8, dict(compression='lzw', planarconfig='separate', photometric='rgb')),
        ('u16_tiled_edges_lzw.tif', (2, 77, 61), np.uint16, dict(compression='lzw', tile=(32, 48))),
        ('u16_bigtiff.tif', (3, 20, 30), np.uint16, dict(bigtiff=True, compression='zlib')),
        ('rgb_chunky_deflate_rowsperstrip.tif', (1, 45, 38, 3), np.uint8, dict(compression='adobe_deflate', photometric='rgb', rowsperstrip=7)),
    ]
    for name, shape, dtype, kw in variants:
        data = field(shape, dtype)
        path = os.path.join(out, name)
        kw = dict(kw)
        kw.setdefault('photometric', 'minisblack')  # pages, not samples, for grey data
        if kw.get('planarconfig') == 'separate':
            data = np.moveaxis(data, -1, 1)  # tifffile wants [page][sample][y][x]
        tifffile.imwrite(path, data, **kw)
        files[name] = tiff_entry(path)

    # JPEG (lossy): grey and RGB (YCbCr, tiled). Decoders may differ by a few LSB.
    grey = field((2, 64, 80), np.uint8)
    tifffile.imwrite(os.path.join(out, 'grey_jpeg.tif'), grey, photometric='minisblack', compression='jpeg', compressionargs={'level': 90})
    files['grey_jpeg.tif'] = tiff_entry(os.path.join(out, 'grey_jpeg.tif'), {'lossy': True})
    rgb = field((1, 64, 96, 3), np.uint8)
    tifffile.imwrite(os.path.join(out, 'rgb_jpeg_tiled.tif'), rgb, compression='jpeg', compressionargs={'level': 90}, photometric='rgb', tile=(32, 32))
    files['rgb_jpeg_tiled.tif'] = tiff_entry(os.path.join(out, 'rgb_jpeg_tiled.tif'), {'lossy': True})

    # ImageJ hyperstack metadata: spacing and unit.
    ij = field((5, 24, 20), np.uint16)
    tifffile.imwrite(os.path.join(out, 'imagej_spacing.tif'), ij, imagej=True, resolution=(1 / 0.25, 1 / 0.5),
                     metadata={'spacing': 2.5, 'unit': 'um', 'axes': 'ZYX'})
    files['imagej_spacing.tif'] = tiff_entry(os.path.join(out, 'imagej_spacing.tif'), {'spacing': [0.25, 0.5, 2.5], 'unit': 'um'})

    # A stack of single-page files whose names sort differently as text and as numbers.
    stack = field((12, 18, 22), np.uint16)
    stack_dir = os.path.join(out, 'stack')
    os.makedirs(stack_dir, exist_ok=True)
    names = []
    for i in range(12):
        n = f'slice{i + 1}.tif'
        tifffile.imwrite(os.path.join(stack_dir, n), stack[i], compression='zlib' if i % 2 else None)
        names.append(n)
    back = np.stack([tifffile.imread(os.path.join(stack_dir, n)) for n in names])
    files['stack/'] = {'files': names, 'pages': 12, 'width': 22, 'height': 18, 'dtype': 'uint16',
                       'sha256_pyxs': sha(back), 'min': float(back.min()), 'max': float(back.max()),
                       'mean': float(back.astype(np.float64).mean())}

    # Files this build must refuse with a clear message.
    bool_img = rng.random((20, 30)) > 0.5
    tifffile.imwrite(os.path.join(out, 'unsupported_1bit.tif'), bool_img)
    tifffile.imwrite(os.path.join(out, 'unsupported_f16.tif'), field((1, 8, 8), np.float16), photometric='minisblack')
    tifffile.imwrite(os.path.join(out, 'unsupported_zstd.tif'), field((1, 16, 16), np.uint16), photometric='minisblack', compression='zstd')
    files['unsupported'] = {
        'unsupported_1bit.tif': 'unsupported sample size: 1 bits per sample',
        'unsupported_f16.tif': 'unsupported 16-bit floating-point samples',
        'unsupported_zstd.tif': 'unsupported compression 50000',
    }
    return files


def las_entry(path):
    las = laspy.read(path)
    h = las.header
    n = len(las.points)
    e = {
        'point_count': n,
        'las_version': f'{h.version.major}.{h.version.minor}',
        'point_format': h.point_format.id,
        'point_record_length': h.point_format.size,
        'scales': [float(s) for s in h.scales],
        'offsets': [float(o) for o in h.offsets],
        'first3_XYZ_int': [[int(las.X[i]), int(las.Y[i]), int(las.Z[i])] for i in range(3)],
        'classification': [int(c) for c in np.asarray(las.classification)[:5]],
        'intensity': [int(c) for c in np.asarray(las.intensity)[:5]],
        'points_record_sha256': hashlib.sha256(las.points.array.tobytes()).hexdigest(),
    }
    if 'red' in las.point_format.dimension_names:
        e['first3_rgb'] = [[int(las.red[i]), int(las.green[i]), int(las.blue[i])] for i in range(3)]
    return e


def make_las(out):
    rng = np.random.default_rng(11)
    files = {}
    n = 5000
    for fmt in (6, 7, 8):
        header = laspy.LasHeader(point_format=fmt, version='1.4')
        header.scales = [0.001, 0.001, 0.001]
        header.offsets = [500000.0, 4100000.0, 100.0]
        las = laspy.LasData(header)
        las.x = 500000 + rng.random(n) * 300
        las.y = 4100000 + rng.random(n) * 200
        las.z = 100 + rng.random(n) * 40
        las.intensity = rng.integers(0, 65535, n, dtype=np.uint16)
        # Extended classes above 31 exist only in formats 6-10.
        las.classification = rng.integers(0, 64, n, dtype=np.uint8)
        las.return_number = rng.integers(1, 4, n, dtype=np.uint8)
        las.number_of_returns = np.maximum(las.return_number, rng.integers(1, 6, n, dtype=np.uint8))
        las.gps_time = np.sort(rng.random(n) * 1000)
        las.scan_angle = rng.integers(-3000, 3000, n, dtype=np.int16)
        las.point_source_id = rng.integers(0, 100, n, dtype=np.uint16)
        if fmt >= 7:
            las.red = rng.integers(0, 65535, n, dtype=np.uint16)
            las.green = rng.integers(0, 65535, n, dtype=np.uint16)
            las.blue = rng.integers(0, 65535, n, dtype=np.uint16)
        if fmt == 8:
            las.nir = rng.integers(0, 65535, n, dtype=np.uint16)
        las.update_header()
        for ext, compress in (('las', False), ('laz', True)):
            name = f'las14_format{fmt}.{ext}'
            path = os.path.join(out, name)
            las.write(path, laz_backend=laspy.LazBackend.Lazrs if compress else None)
            files[name] = las_entry(path)
    return files


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    result = {'tiff': make_tiffs(out), 'las': make_las(out)}
    with open(os.path.join(out, 'expected.json'), 'w') as f:
        json.dump(result, f, indent=1)


if __name__ == '__main__':
    main()
