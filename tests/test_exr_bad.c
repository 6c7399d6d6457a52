/* test_exr_bad.c — the EXR volume reader rejects attributes that cannot be
 * a volume's axes (found by fuzz_exr: a t_us of 2e257 was converted to
 * int64, undefined behaviour). A good file is written, one attribute value
 * patched in its bytes, and read back. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_recon.h"

/* Overwrite the double value of attribute `name` in an EXR header:
 * name\0 "double"\0 int32 size (8) value. Returns 1 when found. */
static int patch_double(unsigned char *buf, size_t n, const char *name, double value)
{
  size_t nl = strlen(name);
  for (size_t i = 0; i + nl + 8 + 4 + 8 <= n; i++) {
    if (memcmp(buf + i, name, nl + 1) == 0 && memcmp(buf + i + nl + 1, "double", 7) == 0) {
      memcpy(buf + i + nl + 1 + 7 + 4, &value, 8); /* little-endian host, as EXR */
      return 1;
    }
  }
  return 0;
}

/* Write the n bytes of buf as a file and read it back as a volume: it must
 * be refused with ELFM_ERR_RANGE, no volume, and the file named. `what`
 * says which patch (for the message). */
static void expect_range_error(const unsigned char *buf, size_t n, const char *what)
{
  const char *path = "exr_bad_patched.exr";
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (f) {
    fwrite(buf, 1, n, f);
    fclose(f);
  }
  elfm_volume *v = NULL;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_status s = elfm_volume_read_exr(path, &v, &err);
  CHECK_MSG(s == ELFM_ERR_RANGE && v == NULL, "%s: got %s (%s)", what, elfm_status_str(s),
            err.message);
  CHECK_MSG(strstr(err.file, "exr_bad_patched.exr") != NULL, "%s: error names '%s'", what,
            err.file);
  elfm_volume_free(v);
  remove(path);
}

static void expect_rejected(const unsigned char *good, size_t n, const char *attr, double value)
{
  unsigned char *buf = malloc(n);
  memcpy(buf, good, n);
  CHECK_MSG(patch_double(buf, n, attr, value), "attribute %s not found", attr);
  char what[80];
  snprintf(what, sizeof what, "%s = %g", attr, value);
  expect_range_error(buf, n, what);
  free(buf);
}

/* Overwrite the dataWindow box (4 x int32) and read back: refused before
 * anything of the claimed size is allocated. */
static void expect_window_rejected(const unsigned char *good, size_t n, int32_t x0, int32_t y0,
                                   int32_t x1, int32_t y1)
{
  static const char key[] = "dataWindow\0box2i"; /* name\0 type\0 size box */
  unsigned char *buf = malloc(n);
  memcpy(buf, good, n);
  int found = 0;
  for (size_t i = 0; i + sizeof key + 4 + 16 <= n && !found; i++)
    if (memcmp(buf + i, key, sizeof key) == 0) {
      int32_t box[4] = {x0, y0, x1, y1};
      memcpy(buf + i + sizeof key + 4, box, sizeof box);
      found = 1;
    }
  CHECK(found);
  char what[80];
  snprintf(what, sizeof what, "window %d,%d..%d,%d", x0, y0, x1, y1);
  expect_range_error(buf, n, what);
  free(buf);
}

int main(void)
{
  elfm_error err;
  elfm_volume *v = elfm_volume_create(4, 3, 2, 0.926, -2.0, 2.0, &err);
  CHECK(v != NULL);
  if (!v) return check_report();
  for (int i = 0; i < 24; i++) v->data[i] = (float)i;
  v->t_us = 1000000000000;
  const char *path = "exr_bad_good.exr";
  CHECK_OK(elfm_volume_write_exr(v, path, &err), &err);
  elfm_volume_free(v);

  FILE *f = fopen(path, "rb");
  CHECK(f != NULL);
  if (!f) return check_report();
  unsigned char good[1 << 16];
  size_t n = fread(good, 1, sizeof good, f);
  fclose(f);
  CHECK(n > 100 && n < sizeof good);

  /* The unpatched file reads back (t_us near 1e12 exactly). */
  elfm_volume *back = NULL;
  CHECK_OK(elfm_volume_read_exr(path, &back, &err), &err);
  if (back) CHECK_EQ_INT(back->t_us, 1000000000000LL);
  elfm_volume_free(back);

  expect_rejected(good, n, "t_us", 2.36e257);
  expect_rejected(good, n, "t_us", -1e19);
  expect_rejected(good, n, "um_per_px", 0.0);
  expect_rejected(good, n, "um_per_px", -0.5);
  expect_rejected(good, n, "z_step_um", 0.0);
  expect_rejected(good, n, "z_min_um", 1.0 / 0.0);

  /* A data window that claims more voxels than a volume may have (found by
   * fuzz_exr: 60000 x 60000 was passed to calloc, 14 GB). */
  expect_window_rejected(good, n, 0, 0, 59999, 59999);
  expect_window_rejected(good, n, 0, 0, 30000, 4999);  /* 150 M voxels x 2 planes */
  expect_window_rejected(good, n, 0, 0, 99999, 1); /* a side over 65535 px */

  /* The cap itself, on elfm_volume_create: one voxel over is refused with
   * ELFM_ERR_RANGE, without allocating. */
  elfm_error_clear(&err);
  CHECK(elfm_volume_create(1 << 14, 1 << 13, 2, 1, 0, 1, &err) == NULL);
  CHECK_EQ_INT(err.code, ELFM_ERR_RANGE);
  remove(path);
  return check_report();
}
