/*
 * Thin C API over LLNL zfp 1.0.1 (fetched from the zfpy sdist at build time by
 * wasm/build.mjs) for the WebAssembly module wasm/dist/zfp.{js,wasm}: decode a
 * fixed-rate 3D float32 stream, with zfp's header (what `zfp -h` and
 * zfpy.compress_numpy(..., write_header=True) write) or without one (shape and
 * rate given), into a float32 array, exactly as zfp's serial decoder does
 * (it is zfp's serial decoder). Used by the paper benchmarks
 * (benchmarks/paper/) as the "zfp's C decoder in Wasm" baseline.
 *
 * Errors are reported as a status code and a message (zfp_api_error), never
 * by aborting. The caller owns every buffer.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "zfp.h"

static char error_text[256] = "";

static int fail(int status, const char *message) {
  snprintf(error_text, sizeof error_text, "%s", message);
  return status;
}

/* The message of the last failed call. */
const char *zfp_api_error(void) { return error_text; }

enum {
  ZFP_API_OK = 0,
  ZFP_API_BAD_HEADER = 1,
  ZFP_API_UNSUPPORTED = 2,
  ZFP_API_BAD_SIZE = 3,
  ZFP_API_DECODE_FAILED = 4,
  ZFP_API_NO_MEMORY = 5,
};

/*
 * Header facts of a stream with zfp's header: out[0..2] = nx, ny, nz,
 * out[3] = zfp_type (3 = float), out[4] = dimensionality, out[5] = compression
 * mode (zfp_mode, 2 = fixed rate), out[6] = maxbits (bits per block in fixed
 * rate), out[7] = header bits. Returns 0 or an error status.
 */
int zfp_api_info(const void *data, size_t size, uint32_t *out) {
  if (size < 12) return fail(ZFP_API_BAD_HEADER, "shorter than zfp's 96-bit header");
  bitstream *bits = stream_open((void *)data, size);
  zfp_stream *zfp = bits ? zfp_stream_open(bits) : NULL;
  zfp_field *field = zfp_field_alloc();
  int status = ZFP_API_OK;
  if (!bits || !zfp || !field) {
    status = fail(ZFP_API_NO_MEMORY, "out of memory");
  } else {
    size_t header_bits = zfp_read_header(zfp, field, ZFP_HEADER_FULL);
    if (header_bits == 0) {
      status = fail(ZFP_API_BAD_HEADER, "no valid zfp header (magic 'zfp', codec version 5)");
    } else {
      uint maxprec;
      int minexp;
      uint minbits, maxbits;
      zfp_stream_params(zfp, &minbits, &maxbits, &maxprec, &minexp);
      out[0] = (uint32_t)field->nx;
      out[1] = (uint32_t)field->ny;
      out[2] = (uint32_t)field->nz;
      out[3] = (uint32_t)field->type;
      out[4] = (uint32_t)zfp_field_dimensionality(field);
      out[5] = (uint32_t)zfp_stream_compression_mode(zfp);
      out[6] = (uint32_t)maxbits;
      out[7] = (uint32_t)header_bits;
    }
  }
  if (field) zfp_field_free(field);
  if (zfp) zfp_stream_close(zfp);
  if (bits) stream_close(bits);
  return status;
}

static uint64_t bytes_for_bits(uint64_t bits) { return (bits + 7) / 8; }

static int decode_into(zfp_stream *zfp, zfp_field *field, float *out, size_t out_count) {
  if (zfp_stream_compression_mode(zfp) != zfp_mode_fixed_rate)
    return fail(ZFP_API_UNSUPPORTED, "not a fixed-rate stream (only fixed-rate zfp is supported)");
  if (field->type != zfp_type_float) return fail(ZFP_API_UNSUPPORTED, "not float32 data");
  if (zfp_field_dimensionality(field) != 3) return fail(ZFP_API_UNSUPPORTED, "not a 3D field");
  if (zfp_field_size(field, NULL) != out_count) return fail(ZFP_API_BAD_SIZE, "the output array does not hold nx*ny*nz floats");
  zfp_field_set_pointer(field, out);
  if (zfp_decompress(zfp, field) == 0) return fail(ZFP_API_DECODE_FAILED, "zfp_decompress failed");
  return ZFP_API_OK;
}

/*
 * Decodes a fixed-rate 3D float32 stream that starts with zfp's full header
 * into out (out_count = nx*ny*nz floats, x fastest). Returns 0 or an error status.
 */
int zfp_api_decode(const void *data, size_t size, float *out, size_t out_count) {
  if (size < 12) return fail(ZFP_API_BAD_HEADER, "shorter than zfp's 96-bit header");
  bitstream *bits = stream_open((void *)data, size);
  zfp_stream *zfp = bits ? zfp_stream_open(bits) : NULL;
  zfp_field *field = zfp_field_alloc();
  int status;
  size_t header_bits = 0;
  if (!bits || !zfp || !field) {
    status = fail(ZFP_API_NO_MEMORY, "out of memory");
  } else if ((header_bits = zfp_read_header(zfp, field, ZFP_HEADER_FULL)) == 0) {
    status = fail(ZFP_API_BAD_HEADER, "no valid zfp header (magic 'zfp', codec version 5)");
  } else {
    uint minbits, maxbits, maxprec;
    int minexp;
    zfp_stream_params(zfp, &minbits, &maxbits, &maxprec, &minexp);
    /* Fixed rate: every block takes maxbits, so the stream's length is known up front. */
    size_t blocks = ((field->nx + 3) / 4) * ((field->ny + 3) / 4) * ((field->nz + 3) / 4);
    if (zfp_stream_compression_mode(zfp) == zfp_mode_fixed_rate && bytes_for_bits(header_bits + (uint64_t)blocks * maxbits) > size)
      status = fail(ZFP_API_BAD_SIZE, "the stream is shorter than its header promises (truncated)");
    else
      status = decode_into(zfp, field, out, out_count);
  }
  if (field) zfp_field_free(field);
  if (zfp) zfp_stream_close(zfp);
  if (bits) stream_close(bits);
  return status;
}

/*
 * Decodes a header-less fixed-rate stream of an nx*ny*nz float32 field at
 * `rate` bits per value (zfp_stream_set_rate(..., align = 0), as zfpy does).
 */
int zfp_api_decode_raw(const void *data, size_t size, uint32_t nx, uint32_t ny, uint32_t nz, double rate, float *out, size_t out_count) {
  zfp_field *field = zfp_field_3d(out, zfp_type_float, nx, ny, nz);
  bitstream *bits = stream_open((void *)data, size);
  zfp_stream *zfp = bits ? zfp_stream_open(bits) : NULL;
  int status;
  if (!bits || !zfp || !field) {
    status = fail(ZFP_API_NO_MEMORY, "out of memory");
  } else {
    zfp_stream_set_rate(zfp, rate, zfp_type_float, 3, zfp_false);
    size_t blocks = ((size_t)(nx + 3) / 4) * ((ny + 3) / 4) * ((nz + 3) / 4);
    uint minbits, maxbits, maxprec;
    int minexp;
    zfp_stream_params(zfp, &minbits, &maxbits, &maxprec, &minexp);
    if (bytes_for_bits((uint64_t)blocks * maxbits) > size)
      status = fail(ZFP_API_BAD_SIZE, "the stream is shorter than the shape and rate need");
    else
      status = decode_into(zfp, field, out, out_count);
  }
  if (field) zfp_field_free(field);
  if (zfp) zfp_stream_close(zfp);
  if (bits) stream_close(bits);
  return status;
}
