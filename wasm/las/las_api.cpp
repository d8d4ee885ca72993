// Thin C API over LASzip's reader (laszip_api.h) for JavaScript.
//
// The file's bytes are copied once into the Wasm heap by the caller (malloc +
// HEAPU8.set) and read in place through a std::streambuf over that memory, so
// LASzip sees a seekable std::istream and no further copy is made. Points come
// out in chunks: positions as float32 relative to the centre of the header's
// bounds (UTM coordinates keep their centimetres), RGB, intensity,
// classification, and optionally the raw integer XYZ and the point records in
// uncompressed LAS layout (which tests hash against laspy).
//
// Every function reports failure through las_error(); none aborts.

#include <laszip_api.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <new>
#include <streambuf>

// The same file builds natively for the benchmark's native baseline.
#ifdef __EMSCRIPTEN__
#include <emscripten/emscripten.h>
#else
#define EMSCRIPTEN_KEEPALIVE
#endif

// LASzip reports warnings (e.g. about a corrupt chunk table) through a
// message handler that writes to stderr by default; this module has no file
// system, so stdio would fail inside the glue. Declared here from LASzip's
// lasmessage.hpp (not on the include path of the module build).
#include <laszip_common.h>
typedef void (*LASMessageHandler)(LAS_MESSAGE_TYPE type, const char* msg, void* user_data);
void set_las_message_handler(LASMessageHandler callback, void* user_data);

#ifdef __EMSCRIPTEN__
// This module has no file system. LASzip's malloc_las reads /proc/meminfo
// before every allocation above 1 MB, and the stdio read of a file the glue
// cannot serve fails inside the glue; so no file ever opens here (LASzip then
// skips its free-memory warning and allocates as usual).
extern "C" FILE* fopen(const char*, const char*) { return nullptr; }
#endif

namespace {

// LASzip's messages are dropped: failures come back through laszip_get_error.
void ignore_message(LAS_MESSAGE_TYPE, const char*, void*) {}

// A read-only, seekable stream buffer over memory we do not own.
class MemoryBuffer : public std::streambuf {
 public:
  MemoryBuffer(const uint8_t* data, size_t size) {
    char* p = reinterpret_cast<char*>(const_cast<uint8_t*>(data));
    setg(p, p, p + size);
  }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
    off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : egptr() - eback();
    off_type target = base + off;
    if (target < 0 || target > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + target, egptr());
    return pos_type(target);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
  // Lets istream::read copy large blocks with memcpy instead of byte by byte.
  std::streamsize xsgetn(char* s, std::streamsize n) override {
    std::streamsize avail = egptr() - gptr();
    if (n > avail) n = avail;
    std::memcpy(s, gptr(), static_cast<size_t>(n));
    gbump(static_cast<int>(n));
    return n;
  }
};

struct LasReader {
  uint8_t* data;  // owned: malloc'ed by the caller, freed by las_close
  MemoryBuffer buffer;
  std::istream stream;
  laszip_POINTER laszip = nullptr;
  laszip_header* header = nullptr;
  laszip_point* point = nullptr;
  bool open = false;
  laszip_BOOL compressed = 0;
  int64_t count = 0;
  int64_t next = 0;  // index of the next point to read
  double centre[3] = {0, 0, 0};
  bool check_bounds = false;  // the header's bounds are finite and ordered
  int64_t outside = 0;        // points read so far that lie outside them
  char error[600] = {0};

  LasReader(uint8_t* bytes, size_t size) : data(bytes), buffer(bytes, size), stream(&buffer) {}
};

void set_error(LasReader* r, const char* what, bool with_laszip_message) {
  laszip_CHAR* detail = nullptr;
  if (with_laszip_message && r->laszip) laszip_get_error(r->laszip, &detail);
  if (detail && detail[0])
    std::snprintf(r->error, sizeof(r->error), "%s: %s", what, detail);
  else
    std::snprintf(r->error, sizeof(r->error), "%s", what);
}

bool has_rgb(int format) { return format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10; }
bool has_gps(int format) { return format == 1 || format >= 3; }
bool has_nir(int format) { return format == 8 || format == 10; }
bool has_wave(int format) { return format == 4 || format == 5 || format == 9 || format == 10; }

// Size of the standard fields of a point format (without extra bytes).
int base_record_length(int format) {
  static const int sizes[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return format >= 0 && format <= 10 ? sizes[format] : 0;
}

inline uint8_t* put_u8(uint8_t* p, uint8_t v) { *p = v; return p + 1; }
inline uint8_t* put_u16(uint8_t* p, uint16_t v) { std::memcpy(p, &v, 2); return p + 2; }
inline uint8_t* put_i32(uint8_t* p, int32_t v) { std::memcpy(p, &v, 4); return p + 4; }
inline uint8_t* put_f64(uint8_t* p, double v) { std::memcpy(p, &v, 8); return p + 8; }

// Writes one point in the uncompressed LAS record layout of its format
// (Wasm is little-endian like LAS). Returns the record length written.
int write_record(const laszip_point* pt, int format, int record_length, uint8_t* out) {
  uint8_t* p = out;
  p = put_i32(p, pt->X);
  p = put_i32(p, pt->Y);
  p = put_i32(p, pt->Z);
  p = put_u16(p, pt->intensity);
  if (format <= 5) {
    p = put_u8(p, uint8_t(pt->return_number | (pt->number_of_returns << 3) | (pt->scan_direction_flag << 6) | (pt->edge_of_flight_line << 7)));
    p = put_u8(p, uint8_t(pt->classification | (pt->synthetic_flag << 5) | (pt->keypoint_flag << 6) | (pt->withheld_flag << 7)));
    p = put_u8(p, uint8_t(pt->scan_angle_rank));
    p = put_u8(p, pt->user_data);
    p = put_u16(p, pt->point_source_ID);
    if (has_gps(format)) p = put_f64(p, pt->gps_time);
    if (has_rgb(format)) {
      p = put_u16(p, pt->rgb[0]);
      p = put_u16(p, pt->rgb[1]);
      p = put_u16(p, pt->rgb[2]);
    }
  } else {
    p = put_u8(p, uint8_t(pt->extended_return_number | (pt->extended_number_of_returns << 4)));
    p = put_u8(p, uint8_t(pt->extended_classification_flags | (pt->extended_scanner_channel << 4) | (pt->scan_direction_flag << 6) |
                          (pt->edge_of_flight_line << 7)));
    p = put_u8(p, pt->extended_classification);
    p = put_u8(p, pt->user_data);
    p = put_u16(p, uint16_t(pt->extended_scan_angle));
    p = put_u16(p, pt->point_source_ID);
    p = put_f64(p, pt->gps_time);
    if (has_rgb(format)) {
      p = put_u16(p, pt->rgb[0]);
      p = put_u16(p, pt->rgb[1]);
      p = put_u16(p, pt->rgb[2]);
    }
    if (has_nir(format)) p = put_u16(p, pt->rgb[3]);
  }
  if (has_wave(format)) {
    std::memcpy(p, pt->wave_packet, 29);
    p += 29;
  }
  int written = int(p - out);
  int extra = record_length - written;
  if (extra > 0) {
    int have = pt->extra_bytes && pt->num_extra_bytes > 0 ? pt->num_extra_bytes : 0;
    int n = have < extra ? have : extra;
    if (n > 0) std::memcpy(p, pt->extra_bytes, size_t(n));
    if (extra > n) std::memset(p + n, 0, size_t(extra - n));
  }
  return record_length;
}

// Little-endian field readers for the raw header (the file is at least 227 bytes when used).
inline uint16_t get_u16(const uint8_t* p) { uint16_t v; std::memcpy(&v, p, 2); return v; }
inline uint32_t get_u32(const uint8_t* p) { uint32_t v; std::memcpy(&v, p, 4); return v; }
inline uint64_t get_u64(const uint8_t* p) { uint64_t v; std::memcpy(&v, p, 8); return v; }
inline double get_f64(const uint8_t* p) { double v; std::memcpy(&v, p, 8); return v; }

// The largest point count a header may announce: above 2^53 a JavaScript
// number cannot even hold it exactly.
const uint64_t MAX_POINT_COUNT = (uint64_t(1) << 53) - 1;

// The LAZ chunk table (LASzip's layout: at the start of the point data the
// 64-bit position of the table, -1 meaning "in the last 8 bytes"; at the
// table a version (0) and the chunk count). LASzip allocates 8 bytes per
// chunk from that count before it decodes the table: in wasm32 the product
// wraps past 4 GiB (a heap overflow), and below that a flipped bit asks for
// hundreds of MB. Every chunk holds at least one point and one byte, so the
// count is bounded by the points and by the bytes before the table.
bool check_chunk_table(const uint8_t* d, uint64_t size, uint64_t offset, uint64_t count, char* msg, size_t cap) {
  const uint64_t chunks_start = offset + 8;
  if (chunks_start > size) {
    std::snprintf(msg, cap, "truncated LAZ file: no room for the chunk table's position after byte %llu", (unsigned long long)offset);
    return false;
  }
  uint64_t table = get_u64(d + offset);
  if (table == ~uint64_t(0) && size >= chunks_start + 8) table = get_u64(d + size - 8);
  // A compressor interrupted before writing the table: LASzip rebuilds it while reading.
  if (table + 8 == chunks_start) return true;
  // A table outside the file (a truncated file): LASzip cannot seek there and
  // reports the first point it cannot read, as for any truncated file.
  if (table < chunks_start || table > size || size - table < 8) return true;
  const uint64_t chunks = get_u32(d + table + 4);
  const uint64_t limit = std::min<uint64_t>({table - chunks_start, std::max<uint64_t>(count, 1), uint64_t(1) << 26});
  if (chunks > limit) {
    std::snprintf(msg, cap, "corrupt LAZ file: the chunk table announces %llu chunks for %llu points in %llu bytes of compressed points",
                  (unsigned long long)chunks, (unsigned long long)count, (unsigned long long)(table - chunks_start));
    return false;
  }
  return true;
}

// Checks every size in the raw header against the file's length before
// LASzip sees it: LASzip allocates from these fields (the VLR array, the
// bytes between the VLRs and the point data, each EVLR) and reports some
// inconsistencies through stdio, which this module does not have. All
// arithmetic in 64 bits. Writes the problem to `msg` and returns false.
bool check_layout(const uint8_t* d, uint64_t size, char* msg, size_t cap) {
  if (size < 227) {
    std::snprintf(msg, cap, "truncated file: %llu bytes, shorter than a LAS header (227 bytes)", (unsigned long long)size);
    return false;
  }
  const unsigned minor = d[25];
  const uint64_t header_size = get_u16(d + 94);
  const uint64_t offset = get_u32(d + 96);
  const uint64_t vlr_count = get_u32(d + 100);
  const uint64_t record_length = get_u16(d + 105);
  if (header_size < 227 || header_size > size) {
    std::snprintf(msg, cap, "corrupt header: header size %llu (must be at least 227 and within the file's %llu bytes)",
                  (unsigned long long)header_size, (unsigned long long)size);
    return false;
  }
  if (offset < header_size || offset > size) {
    std::snprintf(msg, cap, "corrupt header: the point data is said to start at byte %llu, %s", (unsigned long long)offset,
                  offset < header_size ? "inside the header" : "past the end of the file");
    return false;
  }
  // Variable-length records lie between the header and the point data, 54 bytes each plus their payload.
  uint64_t at = header_size;
  bool laszip_vlr = false;
  for (uint64_t i = 0; i < vlr_count; i++) {
    if (at + 54 > offset || at + 54 + get_u16(d + at + 20) > offset) {
      std::snprintf(msg, cap, "corrupt header: it announces %llu variable-length records, but record %llu does not fit before the point data (byte %llu)",
                    (unsigned long long)vlr_count, (unsigned long long)(i + 1), (unsigned long long)offset);
      return false;
    }
    // LASzip's own VLR lists its compressed items (6 bytes each) after a 34-byte
    // preamble; LASzip reads as many as it says, past the record when it lies.
    const uint64_t len = get_u16(d + at + 20);
    if (get_u16(d + at + 18) == 22204 && std::memcmp(d + at + 2, "laszip encoded", 14) == 0) {
      if (len < 34 || 34 + 6 * uint64_t(get_u16(d + at + 54 + 32)) > len) {
        std::snprintf(msg, cap, "corrupt LAZ header: the compression record (%llu bytes) lists %u items, more than it holds",
                      (unsigned long long)len, len < 34 ? 0u : unsigned(get_u16(d + at + 54 + 32)));
        return false;
      }
      laszip_vlr = true;
    }
    at += 54 + len;
  }
  const bool v14 = minor >= 4 && header_size >= 375;
  if (v14) {
    // Extended VLRs (LAS 1.4) follow the point data, 60 bytes each plus a 64-bit payload length.
    const uint64_t evlr_start = get_u64(d + 235);
    const uint64_t evlr_count = get_u32(d + 243);
    uint64_t e = evlr_start;
    for (uint64_t i = 0; i < evlr_count; i++) {
      if (e > size || size - e < 60 || get_u64(d + e + 20) > size - e - 60) {
        std::snprintf(msg, cap, "corrupt header: it announces %llu extended variable-length records, but record %llu does not fit in the file",
                      (unsigned long long)evlr_count, (unsigned long long)(i + 1));
        return false;
      }
      e += 60 + get_u64(d + e + 20);
    }
  }
  const uint64_t legacy = get_u32(d + 107);
  const uint64_t count = legacy ? legacy : v14 ? get_u64(d + 247) : 0;
  if (count > MAX_POINT_COUNT) {
    std::snprintf(msg, cap, "corrupt header: it announces %llu points, an impossible count", (unsigned long long)count);
    return false;
  }
  if (record_length == 0) {
    std::snprintf(msg, cap, "corrupt header: the point record length is 0");
    return false;
  }
  // Without compression every record must be in the file (a division: no product can wrap).
  const bool compressed = (d[104] & 0x80) != 0;
  if (!compressed && count > (size - offset) / record_length) {
    std::snprintf(msg, cap, "truncated file: the header announces %llu points of %llu bytes from byte %llu, but the file has %llu bytes",
                  (unsigned long long)count, (unsigned long long)record_length, (unsigned long long)offset, (unsigned long long)size);
    return false;
  }
  if (compressed && laszip_vlr && !check_chunk_table(d, size, offset, count, msg, cap)) return false;
  const char* axis = "xyz";
  for (int a = 0; a < 3; a++) {
    const double scale = get_f64(d + 131 + 8 * a), offset_a = get_f64(d + 155 + 8 * a);
    if (!std::isfinite(scale) || scale == 0) {
      std::snprintf(msg, cap, "corrupt header: the %c scale factor is %g (it must be a finite, non-zero number)", axis[a], scale);
      return false;
    }
    if (!std::isfinite(offset_a)) {
      std::snprintf(msg, cap, "corrupt header: the %c offset is %g (it must be finite)", axis[a], offset_a);
      return false;
    }
  }
  return true;
}

bool finite_bounds(const laszip_header* h) {
  const double v[6] = {h->min_x, h->min_y, h->min_z, h->max_x, h->max_y, h->max_z};
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return h->min_x <= h->max_x && h->min_y <= h->max_y && h->min_z <= h->max_z;
}

}  // namespace

extern "C" {

// Takes ownership of `data` (allocated with malloc); las_close frees it.
// Always returns a handle unless out of memory; check las_error().
EMSCRIPTEN_KEEPALIVE LasReader* las_open(uint8_t* data, uint32_t size) {
  LasReader* r = new (std::nothrow) LasReader(data, size);
  if (!r) {
    std::free(data);
    return nullptr;
  }
  if (size < 4 || std::memcmp(data, "LASF", 4) != 0) {
    set_error(r, "not a LAS/LAZ file (the file does not start with the signature \"LASF\")", false);
    return r;
  }
  char layout[300];
  if (!check_layout(data, size, layout, sizeof(layout))) {
    set_error(r, layout, false);
    return r;
  }
  set_las_message_handler(ignore_message, nullptr);
  if (laszip_create(&r->laszip) || !r->laszip) {
    set_error(r, "could not create the LASzip reader", false);
    return r;
  }
  if (laszip_open_reader_stream(r->laszip, r->stream, &r->compressed)) {
    set_error(r, "cannot read the LAS header", true);
    return r;
  }
  r->open = true;
  if (laszip_get_header_pointer(r->laszip, &r->header) || laszip_get_point_pointer(r->laszip, &r->point)) {
    set_error(r, "cannot access the LAS header", true);
    return r;
  }
  // As LASzip does: the legacy 32-bit count, or the LAS 1.4 64-bit one when it is 0
  // (both checked against the file and MAX_POINT_COUNT above, in the raw header).
  const uint64_t count = r->header->number_of_point_records ? uint64_t(r->header->number_of_point_records)
                                                            : uint64_t(r->header->extended_number_of_point_records);
  const laszip_header* h = r->header;
  if (count > MAX_POINT_COUNT) {
    set_error(r, "corrupt header: an impossible point count", false);
    return r;
  }
  r->count = int64_t(count);
  if (h->point_data_format > 10) {
    char msg[120];
    std::snprintf(msg, sizeof(msg), "unsupported point data format %d (LAS defines 0 to 10)", int(h->point_data_format));
    set_error(r, msg, false);
    return r;
  }
  if (h->point_data_record_length < base_record_length(h->point_data_format)) {
    char msg[160];
    std::snprintf(msg, sizeof(msg), "corrupt header: point records of %d bytes are too short for point format %d (at least %d bytes)",
                  int(h->point_data_record_length), int(h->point_data_format), base_record_length(h->point_data_format));
    set_error(r, msg, false);
    return r;
  }
  // Without compression, all records must be in the file (64-bit division, no product to wrap).
  if (!r->compressed && count > (uint64_t(size) - std::min<uint64_t>(size, h->offset_to_point_data)) / h->point_data_record_length) {
    char msg[200];
    std::snprintf(msg, sizeof(msg), "truncated file: the header announces %llu points of %d bytes but the file has %u bytes",
                  (unsigned long long)count, int(h->point_data_record_length), size);
    set_error(r, msg, false);
    return r;
  }
  if (finite_bounds(h)) {
    r->check_bounds = true;
    r->centre[0] = 0.5 * (h->min_x + h->max_x);
    r->centre[1] = 0.5 * (h->min_y + h->max_y);
    r->centre[2] = 0.5 * (h->min_z + h->max_z);
  } else {
    r->centre[0] = h->x_offset;
    r->centre[1] = h->y_offset;
    r->centre[2] = h->z_offset;
  }
  return r;
}

// Empty string when all is well.
EMSCRIPTEN_KEEPALIVE const char* las_error(LasReader* r) { return r ? r->error : "out of memory"; }

// Header facts as doubles, in the order of LAS_INFO_FIELDS in src/loaders/las.ts.
EMSCRIPTEN_KEEPALIVE int las_info(LasReader* r, double* out) {
  if (!r || !r->header) return 1;
  const laszip_header* h = r->header;
  int format = h->point_data_format;
  double v[] = {
      double(r->count),
      double(h->version_major),
      double(h->version_minor),
      double(format),
      double(h->point_data_record_length),
      double(r->compressed ? 1 : 0),
      h->x_scale_factor, h->y_scale_factor, h->z_scale_factor,
      h->x_offset, h->y_offset, h->z_offset,
      h->min_x, h->min_y, h->min_z,
      h->max_x, h->max_y, h->max_z,
      r->centre[0], r->centre[1], r->centre[2],
      double(has_rgb(format) ? 1 : 0),
      double(has_gps(format) ? 1 : 0),
      double(h->number_of_variable_length_records),
      double(h->offset_to_point_data),
      double(h->file_creation_year),
      double(h->file_creation_day),
      double(base_record_length(format)),
  };
  std::memcpy(out, v, sizeof(v));
  return 0;
}

// 0: system identifier, 1: generating software (NUL-terminated copies).
EMSCRIPTEN_KEEPALIVE const char* las_header_string(LasReader* r, int which) {
  static char text[33];
  text[0] = 0;
  if (!r || !r->header) return text;
  const char* src = which == 0 ? r->header->system_identifier : r->header->generating_software;
  std::memcpy(text, src, 32);
  text[32] = 0;
  return text;
}

// Reads up to `n` points into the given arrays (any may be null):
//   positions: float32 x,y,z relative to the centre; rgb: uint16 r,g,b (0 when
//   the format has none); intensity: uint16; classification: uint8;
//   xyz: the raw int32 X,Y,Z; records: point_data_record_length bytes each.
// Returns the number read (0 at the end), or -1 with las_error() set.
EMSCRIPTEN_KEEPALIVE int32_t las_read(LasReader* r, int32_t n, float* positions, uint16_t* rgb, uint16_t* intensity, uint8_t* classification,
                                      int32_t* xyz, uint8_t* records) {
  if (!r || !r->open || r->error[0]) return -1;
  if (n < 0) n = 0;
  int64_t left = r->count - r->next;
  if (n > left) n = int32_t(left);
  const laszip_header* h = r->header;
  const int format = h->point_data_format;
  const bool rgb_present = has_rgb(format);
  const int record_length = h->point_data_record_length;
  const double sx = h->x_scale_factor, sy = h->y_scale_factor, sz = h->z_scale_factor;
  const double ox = h->x_offset - r->centre[0], oy = h->y_offset - r->centre[1], oz = h->z_offset - r->centre[2];
  const laszip_point* pt = r->point;
  // Half a unit of the integer grid: the header's bounds are rounded scaled values.
  const double tx = 0.5 * std::fabs(sx) + 1e-9 * std::max(std::fabs(h->min_x), std::fabs(h->max_x));
  const double ty = 0.5 * std::fabs(sy) + 1e-9 * std::max(std::fabs(h->min_y), std::fabs(h->max_y));
  const double tz = 0.5 * std::fabs(sz) + 1e-9 * std::max(std::fabs(h->min_z), std::fabs(h->max_z));
  for (int32_t i = 0; i < n; i++) {
    if (laszip_read_point(r->laszip)) {
      char msg[160];
      std::snprintf(msg, sizeof(msg), "cannot read point %lld of %lld (truncated or corrupt point data)", (long long)(r->next + 1),
                    (long long)r->count);
      set_error(r, msg, true);
      return -1;
    }
    if (r->check_bounds) {
      const double x = pt->X * sx + h->x_offset, y = pt->Y * sy + h->y_offset, z = pt->Z * sz + h->z_offset;
      if (x < h->min_x - tx || x > h->max_x + tx || y < h->min_y - ty || y > h->max_y + ty || z < h->min_z - tz || z > h->max_z + tz) r->outside++;
    }
    if (positions) {
      // Scale in float64 and subtract the centre before rounding to float32.
      positions[3 * i + 0] = float(pt->X * sx + ox);
      positions[3 * i + 1] = float(pt->Y * sy + oy);
      positions[3 * i + 2] = float(pt->Z * sz + oz);
    }
    if (rgb) {
      rgb[3 * i + 0] = rgb_present ? pt->rgb[0] : 0;
      rgb[3 * i + 1] = rgb_present ? pt->rgb[1] : 0;
      rgb[3 * i + 2] = rgb_present ? pt->rgb[2] : 0;
    }
    if (intensity) intensity[i] = pt->intensity;
    if (classification) classification[i] = format >= 6 ? pt->extended_classification : pt->classification;
    if (xyz) {
      xyz[3 * i + 0] = pt->X;
      xyz[3 * i + 1] = pt->Y;
      xyz[3 * i + 2] = pt->Z;
    }
    if (records) write_record(pt, format, record_length, records + size_t(i) * size_t(record_length));
    r->next++;
  }
  return n;
}

// Points read so far that lie outside the header's bounds (-1: the bounds are not finite or not ordered).
EMSCRIPTEN_KEEPALIVE double las_outside(LasReader* r) { return r && r->check_bounds ? double(r->outside) : -1; }

// Frees the reader, LASzip's state and the file bytes.
EMSCRIPTEN_KEEPALIVE void las_close(LasReader* r) {
  if (!r) return;
  if (r->laszip) {
    if (r->open) laszip_close_reader(r->laszip);
    laszip_destroy(r->laszip);
  }
  std::free(r->data);
  delete r;
}

}  // extern "C"
