// Serial marching cubes in C++: the native and WebAssembly entries of the paper's
// serial comparison (section 3.3.3). Same table (mc_tables.h, generated with
// src/mc/case-table-data.ts from VTK) and the same steps in the same order as
// src/mc/serial-mc.ts, so all three give bit-identical triangle soups:
//   pass 1: case index of every cell (x fastest) and the total vertex count;
//   pass 2: allocate exactly, then each non-empty cell's vertices, where the vertex
//   on an edge (lower corner value v0, upper v1) is lower + t along the edge's axis,
//   t = (iso - v0) / (v1 - v0) in float32, coordinate = float(base) + t in float32.
// Build: benchmarks/serial-mc/build.mjs (g++ -O3 natively, emcc -O3 to Wasm).
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "mc_tables.h"

#ifdef __EMSCRIPTEN__
#include <emscripten/emscripten.h>
#define MC_EXPORT extern "C" EMSCRIPTEN_KEEPALIVE
#else
#define MC_EXPORT extern "C"
#endif

// Returns 0 and a malloc'd soup (xyz per vertex, 3 vertices per triangle; free with
// mc_free) in *positions with its vertex count in *vertex_count; nonzero on bad
// input (1) or allocation failure (2). An empty surface gives a null *positions.
MC_EXPORT int mc_marching_cubes(const float* values, int nx, int ny, int nz, float iso, float** positions,
                                size_t* vertex_count) {
  *positions = nullptr;
  *vertex_count = 0;
  if (nx < 1 || ny < 1 || nz < 1) return 1;
  if (nx < 2 || ny < 2 || nz < 2) return 0;
  const size_t sx = (size_t)nx;
  const size_t sxy = (size_t)nx * (size_t)ny;
  const size_t cells = (size_t)(nx - 1) * (size_t)(ny - 1) * (size_t)(nz - 1);
  uint8_t* cases = (uint8_t*)malloc(cells);
  if (!cases) return 2;

  // Pass 1. The column at x holds the inside bits of (y, z) offsets (0,0), (1,0),
  // (0,1), (1,1) at bits 0, 2, 4, 6; column(i) | column(i + 1) << 1 is the case.
  size_t count = 0;
  size_t cell = 0;
  for (int k = 0; k < nz - 1; k++) {
    for (int j = 0; j < ny - 1; j++) {
      const float* r00 = values + (size_t)j * sx + (size_t)k * sxy;
      const float* r10 = r00 + sx;
      const float* r01 = r00 + sxy;
      const float* r11 = r01 + sx;
      unsigned prev = (r00[0] >= iso ? 1u : 0u) | (r10[0] >= iso ? 4u : 0u) | (r01[0] >= iso ? 16u : 0u) |
                      (r11[0] >= iso ? 64u : 0u);
      for (int i = 1; i < nx; i++) {
        const unsigned next = (r00[i] >= iso ? 1u : 0u) | (r10[i] >= iso ? 4u : 0u) | (r01[i] >= iso ? 16u : 0u) |
                              (r11[i] >= iso ? 64u : 0u);
        const unsigned c = prev | (next << 1);
        cases[cell++] = (uint8_t)c;
        count += MC_CASE_VERTEX_COUNT[c];
        prev = next;
      }
    }
  }
  if (count == 0) {
    free(cases);
    return 0;
  }

  // Pass 2.
  float* out = (float*)malloc(count * 3 * sizeof(float));
  if (!out) {
    free(cases);
    return 2;
  }
  size_t corner_offset[8];
  for (int c = 0; c < 8; c++) corner_offset[c] = (size_t)(c & 1) + (size_t)((c >> 1) & 1) * sx + (size_t)(c >> 2) * sxy;
  float cv[8];
  size_t o = 0;
  cell = 0;
  for (int k = 0; k < nz - 1; k++) {
    for (int j = 0; j < ny - 1; j++) {
      for (int i = 0; i < nx - 1; i++) {
        const unsigned c = cases[cell++];
        const unsigned n = MC_CASE_VERTEX_COUNT[c];
        if (n == 0) continue;
        const float* base = values + (size_t)i + (size_t)j * sx + (size_t)k * sxy;
        for (int q = 0; q < 8; q++) cv[q] = base[corner_offset[q]];
        const int8_t* row = MC_CASE_TRIANGLE_EDGES[c];
        for (unsigned m = 0; m < n; m++) {
          const int e = row[m];
          const unsigned lo = MC_EDGE_CORNERS[e][0];
          const float v0 = cv[lo];
          const float t = (iso - v0) / (cv[MC_EDGE_CORNERS[e][1]] - v0);
          const float x = (float)(i + (int)(lo & 1));
          const float y = (float)(j + (int)((lo >> 1) & 1));
          const float z = (float)(k + (int)(lo >> 2));
          const int axis = e >> 2;
          out[o] = axis == 0 ? x + t : x;
          out[o + 1] = axis == 1 ? y + t : y;
          out[o + 2] = axis == 2 ? z + t : z;
          o += 3;
        }
      }
    }
  }
  free(cases);
  *positions = out;
  *vertex_count = count;
  return 0;
}

MC_EXPORT void mc_free(void* p) { free(p); }

MC_EXPORT void* mc_alloc(size_t bytes) { return malloc(bytes); }

#ifndef __EMSCRIPTEN__
// Native command line: reads a raw volume, runs each isovalue `repeat` times, prints
// JSON with triangle counts, float64 areas and per-run times (ms); --dump DIR writes
// each soup as DIR/soup_<n>.f32 (n = isovalue index) for the tests.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

static double soup_area(const float* p, size_t vertices) {
  double area = 0;
  for (size_t v = 0; v < vertices * 3; v += 9) {
    const double ax = (double)p[v + 3] - p[v], ay = (double)p[v + 4] - p[v + 1], az = (double)p[v + 5] - p[v + 2];
    const double bx = (double)p[v + 6] - p[v], by = (double)p[v + 7] - p[v + 1], bz = (double)p[v + 8] - p[v + 2];
    const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
    area += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
  }
  return area;
}

static int usage() {
  fprintf(stderr,
          "usage: serial_mc FILE NX NY NZ ISO[,ISO...] [--dtype float32|uint8] [--repeat N] [--dump DIR]\n");
  return 2;
}

int main(int argc, char** argv) {
  if (argc < 6) return usage();
  const char* file = argv[1];
  const int nx = atoi(argv[2]), ny = atoi(argv[3]), nz = atoi(argv[4]);
  std::vector<float> isos;
  for (const char* s = argv[5]; *s;) {
    char* end;
    isos.push_back(strtof(s, &end));
    if (end == s) return usage();
    s = *end == ',' ? end + 1 : end;
  }
  std::string dtype = "float32", dump;
  int repeat = 1;
  for (int a = 6; a + 1 < argc; a += 2) {
    if (!strcmp(argv[a], "--dtype")) dtype = argv[a + 1];
    else if (!strcmp(argv[a], "--repeat")) repeat = atoi(argv[a + 1]);
    else if (!strcmp(argv[a], "--dump")) dump = argv[a + 1];
    else return usage();
  }
  if (nx < 1 || ny < 1 || nz < 1 || repeat < 1 || (dtype != "float32" && dtype != "uint8")) return usage();
  const size_t n = (size_t)nx * ny * nz;
  std::vector<float> values(n);
  FILE* f = fopen(file, "rb");
  if (!f) {
    fprintf(stderr, "cannot open %s\n", file);
    return 1;
  }
  size_t got;
  if (dtype == "float32") {
    got = fread(values.data(), sizeof(float), n, f);
  } else {
    std::vector<uint8_t> bytes(n);
    got = fread(bytes.data(), 1, n, f);
    for (size_t i = 0; i < n; i++) values[i] = (float)bytes[i];
  }
  fclose(f);
  if (got != n) {
    fprintf(stderr, "%s: expected %zu values, read %zu\n", file, n, got);
    return 1;
  }
  printf("{\"file\": \"%s\", \"dims\": [%d, %d, %d], \"repeat\": %d, \"results\": [", file, nx, ny, nz, repeat);
  for (size_t q = 0; q < isos.size(); q++) {
    std::vector<double> ms;
    size_t vertices = 0;
    double area = 0;
    for (int r = 0; r < repeat; r++) {
      float* soup;
      const auto t0 = std::chrono::steady_clock::now();
      const int status = mc_marching_cubes(values.data(), nx, ny, nz, isos[q], &soup, &vertices);
      const auto t1 = std::chrono::steady_clock::now();
      if (status != 0) {
        fprintf(stderr, "mc_marching_cubes failed: %d\n", status);
        return 1;
      }
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      if (r == 0) {
        area = soup_area(soup, vertices);
        if (!dump.empty()) {
          const std::string path = dump + "/soup_" + std::to_string(q) + ".f32";
          FILE* out = fopen(path.c_str(), "wb");
          if (!out || fwrite(soup, sizeof(float), vertices * 3, out) != vertices * 3) {
            fprintf(stderr, "cannot write %s\n", path.c_str());
            return 1;
          }
          fclose(out);
        }
      }
      mc_free(soup);
    }
    printf("%s{\"iso\": %.9g, \"triangles\": %zu, \"area\": %.17g, \"ms\": [", q ? ", " : "", (double)isos[q],
           vertices / 3, area);
    for (size_t r = 0; r < ms.size(); r++) printf("%s%.4f", r ? ", " : "", ms[r]);
    printf("]}");
  }
  printf("]}\n");
  return 0;
}
#endif
