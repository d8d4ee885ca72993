/* Native baseline for `npm run bench:loaders`: the same C API (tiff_api.c)
 * and libtiff/zlib/libjpeg sources as the Wasm module, compiled with the host
 * compiler. Usage: tiff_bench FILE REPEATS  ->  one JSON line with per-run ms. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct TiffFile TiffFile;
TiffFile *tiff_open(uint8_t *data, uint32_t size);
const char *tiff_error(TiffFile *f);
int tiff_page_count(TiffFile *f);
double tiff_page_bytes(TiffFile *f, int page);
int tiff_read_page(TiffFile *f, int page, uint8_t *out, double out_size);
void tiff_close(TiffFile *f);

static double now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: tiff_bench FILE REPEATS\n");
    return 2;
  }
  FILE *f = fopen(argv[1], "rb");
  if (!f) {
    fprintf(stderr, "cannot open %s\n", argv[1]);
    return 1;
  }
  fseek(f, 0, SEEK_END);
  long size = ftell(f);
  fseek(f, 0, SEEK_SET);
  uint8_t *file = malloc((size_t)size);
  if (fread(file, 1, (size_t)size, f) != (size_t)size) return 1;
  fclose(f);
  int repeats = atoi(argv[2]);
  printf("{\"file\":\"%s\",\"ms\":[", argv[1]);
  double total_bytes = 0;
  for (int rep = 0; rep < repeats; rep++) {
    double t0 = now_ms();
    uint8_t *data = malloc((size_t)size);
    memcpy(data, file, (size_t)size);
    TiffFile *t = tiff_open(data, (uint32_t)size);
    if (tiff_error(t)[0]) {
      fprintf(stderr, "%s\n", tiff_error(t));
      return 1;
    }
    int pages = tiff_page_count(t);
    /* Like the page: one walk over the pages, each decoded into its place in the volume. */
    double bytes = 0;
    size_t capacity = 0;
    uint8_t *volume = NULL;
    for (int p = 0; p < pages; p++) {
      double n = tiff_page_bytes(t, p);
      if ((size_t)(bytes + n) > capacity) {
        capacity = (size_t)(n * pages);
        if (capacity < (size_t)(bytes + n)) capacity = (size_t)(bytes + n);
        volume = realloc(volume, capacity);
      }
      if (tiff_read_page(t, p, volume + (size_t)bytes, n)) {
        fprintf(stderr, "%s\n", tiff_error(t));
        return 1;
      }
      bytes += n;
    }
    free(volume);
    tiff_close(t);
    total_bytes = bytes;
    printf("%s%.4f", rep ? "," : "", now_ms() - t0);
  }
  printf("],\"decodedBytes\":%.0f}\n", total_bytes);
  free(file);
  return 0;
}
