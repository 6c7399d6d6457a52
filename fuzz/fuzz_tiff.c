/* fuzz_tiff.c — libFuzzer target for the light-field TIFF stack loader
 * (recon/lf_tiff.c): any bytes must give pages or a clean error, never a
 * crash, leak or unbounded allocation. libtiff reads from a path, so each
 * input is written to one temporary file first. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "elfm_recon.h"
#include "fuzz_file_common.h"

/* Frames above 4 Mpixel are refused by the harness (not by the loader,
 * which allows up to 32768^2 pages) to keep each run's memory small. */
#define FUZZ_MAX_PIXELS (4u << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  char path[] = "/tmp/fuzz_tiff_XXXXXX";
  if (fuzz_write_temp(path, data, size) != 0) {
    unlink(path);
    return 0;
  }
  elfm_error err;
  elfm_tiff_stack *s = NULL;
  if (elfm_tiff_open(path, &s, &err) == ELFM_OK) {
    int w = elfm_tiff_width(s), h = elfm_tiff_height(s);
    if ((uint64_t)w * (uint64_t)h <= FUZZ_MAX_PIXELS) {
      elfm_frame *f = elfm_frame_create(w, h, &err);
      int got = 1;
      for (int page = 0; f && got && page < 16; page++)
        if (elfm_tiff_read(s, f, &got, &err) != ELFM_OK) break;
      elfm_frame_free(f);
    }
    elfm_tiff_close(s);
  }
  unlink(path);
  return 0;
}
