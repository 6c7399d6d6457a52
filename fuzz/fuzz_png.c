/* fuzz_png.c — libFuzzer target for the viewer's PNG loader (MIP pictures,
 * gui/png_io.c through libpng): any bytes must give an RGBA picture or a
 * clean error, never a crash, leak or longjmp out of place. */
#include "elfm_gui.h"
#include "fuzz_file_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  char path[] = "/tmp/fuzz_png_XXXXXX";
  if (fuzz_write_temp(path, data, size) == 0) {
    int w = 0, h = 0;
    uint8_t *rgba = NULL;
    elfm_error err;
    if (elfm_png_read_rgba(path, &w, &h, &rgba, &err) == ELFM_OK && w > 0 && h > 0) {
      volatile uint8_t last = rgba[(size_t)w * (size_t)h * 4 - 1];
      (void)last;
    }
    free(rgba);
  }
  unlink(path);
  return 0;
}
