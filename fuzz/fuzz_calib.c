/* fuzz_calib.c — libFuzzer target for the calib.json loader: any bytes must
 * give ELFM_OK or an error, never a crash, leak or undefined behaviour; a
 * calibration that loads must also save and load again identically. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "elfm_recon.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  elfm_error err;
  elfm_calib c;
  elfm_error_clear(&err);
  if (elfm_calib_parse((const char *)data, size, "fuzz", &c, &err) != ELFM_OK) return 0;
  /* What loads is in range: projections are finite. */
  double u, v;
  for (int k = 0; k < c.n_views; k++) {
    elfm_calib_project(&c, k, 10.0, -10.0, c.z_max_um, &u, &v);
    if (u != u || v != v) __builtin_trap();
  }
  if (elfm_calib_n_planes(&c) < 1) __builtin_trap();
  char path[64];
  snprintf(path, sizeof path, "/tmp/fuzz_calib_%d.json", (int)getpid());
  if (elfm_calib_save(&c, path, &err) == ELFM_OK) {
    elfm_calib r;
    if (elfm_calib_load(path, &r, &err) != ELFM_OK) __builtin_trap();
    if (r.n_views != c.n_views || r.um_per_px != c.um_per_px) __builtin_trap();
    for (int k = 0; k < c.n_views; k++)
      if (r.views[k].cx_px != c.views[k].cx_px || r.views[k].dy_px_per_um != c.views[k].dy_px_per_um)
        __builtin_trap();
  }
  unlink(path);
  return 0;
}
