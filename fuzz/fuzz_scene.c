/* fuzz_scene.c — libFuzzer target for the scene loader: any bytes must give
 * a scene or an error, never a crash, leak, hang or undefined behaviour. A
 * scene that loads must answer truth queries with finite positions. */
#include <math.h>
#include <stdint.h>

#include "elfm_datasets.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  elfm_error err;
  elfm_scene *s = NULL;
  elfm_error_clear(&err);
  if (elfm_scene_parse((const char *)data, size, "fuzz", &s, &err) != ELFM_OK) {
    if (s) __builtin_trap(); /* failure leaves *out NULL */
    return 0;
  }
  int64_t t0 = elfm_scene_t0_us(s), d = elfm_scene_duration_us(s);
  int n = elfm_scene_n_objects(s);
  for (int k = 0; k < n && k < 64; k++) {
    for (int q = 0; q <= 4; q++) {
      elfm_truth tr;
      elfm_scene_truth(s, k, t0 + d * q / 4, &tr);
      if (!isfinite(tr.x_um) || !isfinite(tr.y_um) || !isfinite(tr.z_um) ||
          !(tr.brightness >= 0 && tr.brightness <= 1))
        __builtin_trap();
    }
  }
  elfm_scene_free(s);
  return 0;
}
