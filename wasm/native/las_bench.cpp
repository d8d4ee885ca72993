// Native baseline for `npm run bench:loaders`: the same C API (las_api.cpp)
// and LASzip sources as the Wasm module, compiled with the host compiler.
// Usage: las_bench FILE REPEATS  ->  one JSON line with per-run milliseconds.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

struct LasReader;
extern "C" {
LasReader* las_open(uint8_t* data, uint32_t size);
const char* las_error(LasReader* r);
int las_info(LasReader* r, double* out);
int32_t las_read(LasReader* r, int32_t n, float* positions, uint16_t* rgb, uint16_t* intensity, uint8_t* classification, int32_t* xyz,
                 uint8_t* records);
void las_close(LasReader* r);
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: las_bench FILE REPEATS\n");
    return 2;
  }
  FILE* f = std::fopen(argv[1], "rb");
  if (!f) {
    std::fprintf(stderr, "cannot open %s\n", argv[1]);
    return 1;
  }
  std::vector<uint8_t> file;
  uint8_t buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) file.insert(file.end(), buf, buf + n);
  std::fclose(f);
  const int repeats = std::atoi(argv[2]);
  const int chunk = 1 << 18;
  std::vector<float> positions(size_t(chunk) * 3);
  std::vector<uint16_t> rgb(size_t(chunk) * 3), intensity(chunk);
  std::vector<uint8_t> classification(chunk);
  std::printf("{\"file\":\"%s\",\"ms\":[", argv[1]);
  double points = 0;
  for (int rep = 0; rep < repeats; rep++) {
    auto t0 = std::chrono::steady_clock::now();
    // Same work as the page: copy into a private buffer, open, decode all points.
    uint8_t* data = static_cast<uint8_t*>(std::malloc(file.size()));
    std::memcpy(data, file.data(), file.size());
    LasReader* r = las_open(data, uint32_t(file.size()));
    if (las_error(r)[0]) {
      std::fprintf(stderr, "%s\n", las_error(r));
      return 1;
    }
    double info[28];
    las_info(r, info);
    points = info[0];
    int32_t got;
    while ((got = las_read(r, chunk, positions.data(), info[21] ? rgb.data() : nullptr, intensity.data(), classification.data(), nullptr, nullptr)) > 0) {
    }
    if (got < 0) {
      std::fprintf(stderr, "%s\n", las_error(r));
      return 1;
    }
    las_close(r);
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s%.4f", rep ? "," : "", ms);
  }
  std::printf("],\"points\":%.0f}\n", points);
  return 0;
}
