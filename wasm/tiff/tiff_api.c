/* Thin C API over libtiff for JavaScript.
 *
 * The file's bytes are copied once into the Wasm heap by the caller and read
 * in place through TIFFClientOpenExt with memory-backed I/O procedures (and a
 * "map" procedure, so libtiff reads uncompressed strips straight from it).
 * Each page decodes into [y][x][sample] order, samples interleaved, native
 * (little-endian) byte order, whatever the file's layout: strips or tiles,
 * chunky or planar, any compression libtiff was built with (none, LZW,
 * deflate, JPEG, PackBits, ...). Errors are collected per file through
 * libtiff's per-handle error handler and returned by tiff_error(); nothing
 * aborts or prints.
 */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <tiffio.h>

/* The same file builds natively for the benchmark's native baseline. */
#ifdef __EMSCRIPTEN__
#include <emscripten/emscripten.h>
#else
#define EMSCRIPTEN_KEEPALIVE
#endif

typedef struct TiffFile {
  uint8_t *data; /* owned: malloc'ed by the caller, freed by tiff_close */
  uint64_t size;
  uint64_t pos;
  TIFF *tif;
  int pages;
  int current; /* directory libtiff is on, -1 unknown */
  char error[600];
  char description[1 << 16];
} TiffFile;

static void set_error(TiffFile *f, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(f->error, sizeof f->error, fmt, ap);
  va_end(ap);
}

/* libtiff reports problems here; keep the first error, it names the cause. */
static int on_error(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap) {
  TiffFile *f = (TiffFile *)user;
  (void)tif;
  if (f && f->error[0] == 0) {
    char msg[480];
    vsnprintf(msg, sizeof msg, fmt, ap);
    snprintf(f->error, sizeof f->error, "%s%s%s", module ? module : "", module ? ": " : "", msg);
  }
  return 1;
}

static int on_warning(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap) {
  (void)tif, (void)user, (void)module, (void)fmt, (void)ap;
  return 1; /* unknown tags and the like: not the user's concern */
}

static tmsize_t mem_read(thandle_t h, void *buf, tmsize_t n) {
  TiffFile *f = (TiffFile *)h;
  if (n <= 0 || f->pos >= f->size) return 0;
  uint64_t avail = f->size - f->pos;
  if ((uint64_t)n > avail) n = (tmsize_t)avail;
  memcpy(buf, f->data + f->pos, (size_t)n);
  f->pos += (uint64_t)n;
  return n;
}

static tmsize_t mem_write(thandle_t h, void *buf, tmsize_t n) {
  (void)h, (void)buf, (void)n;
  return -1; /* read-only */
}

static toff_t mem_seek(thandle_t h, toff_t off, int whence) {
  TiffFile *f = (TiffFile *)h;
  uint64_t base = whence == SEEK_CUR ? f->pos : whence == SEEK_END ? f->size : 0;
  uint64_t target = base + off; /* libtiff passes negative offsets as wrapped uint64 */
  f->pos = target;
  return target;
}

static int mem_close(thandle_t h) {
  (void)h;
  return 0;
}

static toff_t mem_size(thandle_t h) { return ((TiffFile *)h)->size; }

static int mem_map(thandle_t h, void **base, toff_t *size) {
  TiffFile *f = (TiffFile *)h;
  *base = f->data;
  *size = f->size;
  return 1;
}

static void mem_unmap(thandle_t h, void *base, toff_t size) { (void)h, (void)base, (void)size; }

/* The largest decoded page (bytes): the caller mallocs it in a 32-bit heap. */
#define MAX_PAGE_BYTES ((uint64_t)1 << 30)
/* No codec in this build expands data more than this (deflate ~1032:1, LZW
 * ~2730:1, JPEG far less); a page claiming more is a lie about its size. */
#define MAX_EXPANSION 4096

/* Sum of the byte counts of the current page's strips or tiles, each clamped
 * to the file (0 with tiff_error set when the strile count is impossible). */
static uint64_t data_bytes(TiffFile *f, int *ok) {
  TIFF *t = f->tif;
  const uint32_t striles = TIFFIsTiled(t) ? TIFFNumberOfTiles(t) : TIFFNumberOfStrips(t);
  *ok = 1;
  /* Every strip or tile has an offset and a byte count stored in the file;
   * libtiff's virtual strips of a chopped-up strip are at least 8 KiB each. */
  if ((uint64_t)striles > f->size) {
    set_error(f, "corrupt directory: %u %s claimed in a file of %llu bytes", (unsigned)striles, TIFFIsTiled(t) ? "tiles" : "strips",
              (unsigned long long)f->size);
    *ok = 0;
    return 0;
  }
  uint64_t total = 0;
  for (uint32_t i = 0; i < striles; i++) {
    uint64_t off = TIFFGetStrileOffset(t, i), count = TIFFGetStrileByteCount(t, i);
    if (off < f->size) total += count < f->size - off ? count : f->size - off;
  }
  return total;
}

static int go_to(TiffFile *f, int page) {
  if (page < 0 || page >= f->pages) {
    set_error(f, "page %d does not exist (the file has %d)", page, f->pages);
    return 0;
  }
  if (f->current != page) {
    /* Walking forward one page reads the next IFD; TIFFSetDirectory would
     * re-walk the chain from the first one (quadratic over a stack). */
    int ok = f->current >= 0 && page == f->current + 1 ? TIFFReadDirectory(f->tif) : TIFFSetDirectory(f->tif, (tdir_t)page);
    if (!ok) {
      f->current = -1;
      if (!f->error[0]) set_error(f, "cannot read the directory of page %d", page);
      return 0;
    }
    f->current = page;
  }
  return 1;
}

/* Takes ownership of `data` (allocated with malloc); tiff_close frees it.
 * Always returns a handle unless out of memory; check tiff_error(). */
EMSCRIPTEN_KEEPALIVE TiffFile *tiff_open(uint8_t *data, uint32_t size) {
  TiffFile *f = (TiffFile *)calloc(1, sizeof(TiffFile));
  if (!f) {
    free(data);
    return NULL;
  }
  f->data = data;
  f->size = size;
  f->current = -1;
  static const uint8_t le[4] = {'I', 'I', 42, 0}, be[4] = {'M', 'M', 0, 42}, le_big[4] = {'I', 'I', 43, 0}, be_big[4] = {'M', 'M', 0, 43};
  if (size < 8 || (memcmp(data, le, 4) && memcmp(data, be, 4) && memcmp(data, le_big, 4) && memcmp(data, be_big, 4))) {
    set_error(f, "not a TIFF file (no II*/MM* signature)");
    return f;
  }
  TIFFOpenOptions *opts = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(opts, on_error, f);
  TIFFOpenOptionsSetWarningHandlerExtR(opts, on_warning, f);
  /* A corrupt header must not make libtiff ask for gigabytes. */
  TIFFOpenOptionsSetMaxSingleMemAlloc(opts, (tmsize_t)1 << 30);
  f->tif = TIFFClientOpenExt("memory", "r", (thandle_t)f, mem_read, mem_write, mem_seek, mem_close, mem_size, mem_map, mem_unmap, opts);
  TIFFOpenOptionsFree(opts);
  if (!f->tif) {
    char detail[sizeof f->error];
    snprintf(detail, sizeof detail, "%s", f->error[0] ? f->error : "cannot open the file");
    set_error(f, "truncated or corrupt TIFF (libtiff: %s)", detail);
    return f;
  }
  f->current = 0;
  f->pages = (int)TIFFNumberOfDirectories(f->tif);
  /* A broken link after the last good directory is reported but leaves the
   * pages before it readable. */
  f->error[0] = 0;
  if (f->pages < 1) set_error(f, "the TIFF file has no images");
  return f;
}

EMSCRIPTEN_KEEPALIVE const char *tiff_error(TiffFile *f) { return f ? f->error : "out of memory"; }

EMSCRIPTEN_KEEPALIVE int tiff_page_count(TiffFile *f) { return f ? f->pages : 0; }

/* Page facts as doubles, in the order of PAGE_FIELDS in src/loaders/tiff.ts.
 * Returns 0 on success. */
EMSCRIPTEN_KEEPALIVE int tiff_page_info(TiffFile *f, int page, double *out) {
  if (!f || !f->tif) return 1;
  f->error[0] = 0;
  if (!go_to(f, page)) return 1;
  TIFF *t = f->tif;
  uint32_t width = 0, height = 0, tile_w = 0, tile_h = 0, rows_per_strip = 0, subfile = 0;
  uint16_t bits = 1, spp = 1, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE, photometric = 0, planar = PLANARCONFIG_CONTIG,
           res_unit = RESUNIT_INCH;
  float xres = 0, yres = 0;
  TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(t, TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &compression);
  TIFFGetField(t, TIFFTAG_PHOTOMETRIC, &photometric);
  TIFFGetFieldDefaulted(t, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetFieldDefaulted(t, TIFFTAG_SUBFILETYPE, &subfile);
  int tiled = TIFFIsTiled(t);
  if (tiled) {
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tile_w);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &tile_h);
  } else {
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
  }
  int data_ok = 1;
  const uint64_t stored = data_bytes(f, &data_ok);
  if (!data_ok) return 1;
  int has_xres = TIFFGetField(t, TIFFTAG_XRESOLUTION, &xres);
  int has_yres = TIFFGetField(t, TIFFTAG_YRESOLUTION, &yres);
  TIFFGetFieldDefaulted(t, TIFFTAG_RESOLUTIONUNIT, &res_unit);
  double v[] = {
      width, height, bits, spp, format, compression, photometric, planar, tiled, tile_w, tile_h, rows_per_strip,
      has_xres ? xres : 0, has_yres ? yres : 0, res_unit, subfile, TIFFIsBigEndian(t) ? 1 : 0, TIFFIsBigTIFF(t) ? 1 : 0,
      (double)stored,
  };
  memcpy(out, v, sizeof v);
  return 0;
}

/* The page's ImageDescription (ImageJ keeps its metadata there), or "". */
EMSCRIPTEN_KEEPALIVE const char *tiff_page_description(TiffFile *f, int page) {
  f->description[0] = 0;
  if (!f->tif || !go_to(f, page)) return f->description;
  const char *text = NULL;
  if (TIFFGetField(f->tif, TIFFTAG_IMAGEDESCRIPTION, &text) && text) {
    /* Not strncpy: it would zero-fill the whole 64 KiB for every page. */
    size_t n = strnlen(text, sizeof f->description - 1);
    memcpy(f->description, text, n);
    f->description[n] = 0;
  }
  return f->description;
}

/* Bytes tiff_read_page writes for this page (0 if unsupported, see tiff_error). */
static uint64_t page_bytes(TiffFile *f, uint32_t *w, uint32_t *h, uint16_t *spp, uint16_t *bytes_per_sample) {
  TIFF *t = f->tif;
  uint16_t bits = 1, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE, photometric = 0;
  TIFFGetField(t, TIFFTAG_IMAGEWIDTH, w);
  TIFFGetField(t, TIFFTAG_IMAGELENGTH, h);
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, spp);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &compression);
  TIFFGetField(t, TIFFTAG_PHOTOMETRIC, &photometric);
  if (bits != 8 && bits != 16 && bits != 32 && bits != 64) {
    set_error(f, "unsupported sample size: %u bits per sample (8, 16, 32 and 64 are supported)", bits);
    return 0;
  }
  if (format != SAMPLEFORMAT_UINT && format != SAMPLEFORMAT_INT && format != SAMPLEFORMAT_IEEEFP) {
    set_error(f, "unsupported sample format %u (unsigned, signed integer and IEEE float are supported)", format);
    return 0;
  }
  if (format == SAMPLEFORMAT_IEEEFP && bits != 32 && bits != 64) {
    set_error(f, "unsupported %u-bit floating-point samples (32 and 64 are supported)", bits);
    return 0;
  }
  if (!TIFFIsCODECConfigured(compression)) {
    set_error(f, "unsupported compression %u (this build reads none, LZW, deflate, JPEG, PackBits, CCITT and a few older schemes)", compression);
    return 0;
  }
  if (photometric == PHOTOMETRIC_YCBCR) {
    if (compression != COMPRESSION_JPEG) {
      set_error(f, "unsupported YCbCr image without JPEG compression");
      return 0;
    }
    /* libjpeg converts to RGB, as tifffile/imagecodecs do. */
    TIFFSetField(t, TIFFTAG_JPEGCOLORMODE, JPEGCOLORMODE_RGB);
  }
  *bytes_per_sample = (uint16_t)(bits / 8);
  /* At most 2^32 * 2^32 * 2^16 * 8: fits no integer type, so check in steps. */
  const uint64_t pixels = (uint64_t)*w * *h;
  if (pixels == 0) {
    set_error(f, "the image is empty (%u x %u pixels)", (unsigned)*w, (unsigned)*h);
    return 0;
  }
  if (pixels > MAX_PAGE_BYTES || pixels * *spp * *bytes_per_sample > MAX_PAGE_BYTES) {
    set_error(f, "the page is %u x %u pixels of %u x %u-bit samples (%.2f GiB), more than the largest page this reader decodes (1 GiB)",
              (unsigned)*w, (unsigned)*h, (unsigned)*spp, (unsigned)bits, (double)pixels * *spp * *bytes_per_sample / (1 << 30));
    return 0;
  }
  const uint64_t need = pixels * *spp * *bytes_per_sample;
  int ok = 1;
  const uint64_t stored = data_bytes(f, &ok);
  if (!ok) return 0;
  if (need > stored * (compression == COMPRESSION_NONE ? 1 : MAX_EXPANSION)) {
    if (compression == COMPRESSION_NONE)
      set_error(f, "truncated or corrupt file: the page needs %llu bytes of samples but its strips hold %llu bytes", (unsigned long long)need,
                (unsigned long long)stored);
    else
      set_error(f, "corrupt file: the page claims %llu bytes of samples from only %llu bytes of compressed data", (unsigned long long)need,
                (unsigned long long)stored);
    return 0;
  }
  return need;
}

EMSCRIPTEN_KEEPALIVE double tiff_page_bytes(TiffFile *f, int page) {
  if (!f || !f->tif) return 0;
  f->error[0] = 0;
  if (!go_to(f, page)) return 0;
  uint32_t w = 0, h = 0;
  uint16_t spp = 1, bps = 1;
  return (double)page_bytes(f, &w, &h, &spp, &bps);
}

/* Copies a decoded block (rows x cols pixels, `chunk_spp` samples each, row
 * stride `src_stride` bytes) into the [y][x][s] output at (x0, y0), sample
 * offset `s0` of `spp`. */
static void scatter(uint8_t *out, uint32_t width, uint16_t spp, uint16_t bps, const uint8_t *src, uint64_t src_stride, uint32_t x0,
                    uint32_t y0, uint32_t cols, uint32_t rows, uint16_t s0, uint16_t chunk_spp) {
  const uint64_t pixel = (uint64_t)spp * bps;
  const uint64_t chunk_pixel = (uint64_t)chunk_spp * bps;
  for (uint32_t r = 0; r < rows; r++) {
    uint8_t *dst = out + ((uint64_t)(y0 + r) * width + x0) * pixel + (uint64_t)s0 * bps;
    const uint8_t *s = src + (uint64_t)r * src_stride;
    if (chunk_spp == spp) {
      memcpy(dst, s, (size_t)(cols * pixel));
    } else {
      for (uint32_t c = 0; c < cols; c++) memcpy(dst + c * pixel, s + c * chunk_pixel, (size_t)chunk_pixel);
    }
  }
}

/* Decodes `page` into `out` ([y][x][sample], tiff_page_bytes(page) bytes).
 * Returns 0 on success, 1 with tiff_error() set. */
EMSCRIPTEN_KEEPALIVE int tiff_read_page(TiffFile *f, int page, uint8_t *out, double out_size) {
  if (!f || !f->tif) return 1;
  f->error[0] = 0;
  if (!go_to(f, page)) return 1;
  TIFF *t = f->tif;
  uint32_t width = 0, height = 0;
  uint16_t spp = 1, bps = 1, planar = PLANARCONFIG_CONTIG;
  uint64_t need = page_bytes(f, &width, &height, &spp, &bps);
  if (need == 0) {
    if (!f->error[0]) set_error(f, "page %d is empty", page);
    return 1;
  }
  if (!(out_size >= (double)need)) {
    set_error(f, "output buffer too small for page %d", page);
    return 1;
  }
  TIFFGetFieldDefaulted(t, TIFFTAG_PLANARCONFIG, &planar);
  /* A cut-off file shows as strips or tiles that end past the end of the data. */
  const uint32_t striles = TIFFIsTiled(t) ? TIFFNumberOfTiles(t) : TIFFNumberOfStrips(t);
  for (uint32_t i = 0; i < striles; i++) {
    uint64_t off = TIFFGetStrileOffset(t, i), count = TIFFGetStrileByteCount(t, i);
    if (off > f->size || count > f->size - off) {
      set_error(f, "truncated file: %s %u of page %d ends at byte %llu but the file has %llu bytes", TIFFIsTiled(t) ? "tile" : "strip",
                (unsigned)i, page, (unsigned long long)(off + count), (unsigned long long)f->size);
      return 1;
    }
  }
  const int separate = planar == PLANARCONFIG_SEPARATE && spp > 1;
  const uint16_t chunk_spp = separate ? 1 : spp;
  const uint16_t planes = separate ? spp : 1;

  if (TIFFIsTiled(t)) {
    uint32_t tw = 0, th = 0;
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
    tmsize_t tile_size = TIFFTileSize(t);
    if (tw == 0 || th == 0 || tile_size <= 0) {
      set_error(f, "page %d: invalid tile size", page);
      return 1;
    }
    uint8_t *tile = (uint8_t *)malloc((size_t)tile_size);
    if (!tile) {
      set_error(f, "out of memory for a %lld-byte tile", (long long)tile_size);
      return 1;
    }
    const uint64_t stride = (uint64_t)tw * chunk_spp * bps;
    for (uint16_t s = 0; s < planes; s++)
      for (uint32_t y = 0; y < height; y += th)
        for (uint32_t x = 0; x < width; x += tw) {
          ttile_t index = TIFFComputeTile(t, x, y, 0, s);
          if (TIFFReadEncodedTile(t, index, tile, tile_size) < 0) {
            if (!f->error[0]) set_error(f, "page %d: cannot decode tile %u", page, (unsigned)index);
            free(tile);
            return 1;
          }
          uint32_t cols = width - x < tw ? width - x : tw;
          uint32_t rows = height - y < th ? height - y : th;
          scatter(out, width, spp, bps, tile, stride, x, y, cols, rows, s, chunk_spp);
        }
    free(tile);
  } else {
    uint32_t rows_per_strip = 0;
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
    if (rows_per_strip == 0 || rows_per_strip > height) rows_per_strip = height;
    const uint64_t row_bytes = (uint64_t)width * chunk_spp * bps;
    const uint32_t strips_per_plane = (height + rows_per_strip - 1) / rows_per_strip;
    /* Chunky strips decode in place; planar ones go through a strip buffer. */
    uint8_t *strip = NULL;
    if (separate) {
      strip = (uint8_t *)malloc((size_t)(row_bytes * rows_per_strip));
      if (!strip) {
        set_error(f, "out of memory for a strip");
        return 1;
      }
    }
    for (uint16_t s = 0; s < planes; s++)
      for (uint32_t i = 0; i < strips_per_plane; i++) {
        uint32_t y = i * rows_per_strip;
        uint32_t rows = height - y < rows_per_strip ? height - y : rows_per_strip;
        tmsize_t want = (tmsize_t)(row_bytes * rows);
        uint8_t *dst = separate ? strip : out + (uint64_t)y * row_bytes;
        tstrip_t index = TIFFComputeStrip(t, y, s);
        tmsize_t got = TIFFReadEncodedStrip(t, index, dst, want);
        if (got < 0) {
          if (!f->error[0]) set_error(f, "page %d: cannot decode strip %u", page, (unsigned)index);
          free(strip);
          return 1;
        }
        if (got < want) {
          set_error(f, "page %d: strip %u is truncated (%lld of %lld bytes)", page, (unsigned)index, (long long)got, (long long)want);
          free(strip);
          return 1;
        }
        if (separate) scatter(out, width, spp, bps, strip, row_bytes, 0, y, width, rows, s, 1);
      }
    free(strip);
  }
  /* libtiff reports some decode problems (e.g. a short LZW strip) as errors
   * while still returning data: treat them as failures. */
  return f->error[0] ? 1 : 0;
}

EMSCRIPTEN_KEEPALIVE void tiff_close(TiffFile *f) {
  if (!f) return;
  if (f->tif) TIFFClose(f->tif);
  free(f->data);
  free(f);
}
