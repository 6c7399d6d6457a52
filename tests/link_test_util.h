/* link_test_util.h — what the linker's tests share (include after check.h
 * and elfm_tracker.h). */
#ifndef ELFM_TESTS_LINK_TEST_UTIL_H
#define ELFM_TESTS_LINK_TEST_UTIL_H

#include <string.h>

/* A detection at (x, y, z) um of the given intensity, with the detector's
 * in-focus sigmas (1.6 um laterally, 9 um in z). */
static inline elfm_detection link_test_det(double x, double y, double z, double intensity)
{
  elfm_detection d;
  memset(&d, 0, sizeof d);
  d.x_um = x;
  d.y_um = y;
  d.z_um = z;
  d.intensity = intensity;
  d.sigma_x_um = d.sigma_y_um = 1.6;
  d.sigma_z_um = 9;
  return d;
}

/* Finish the linker, drop its tracks, free it. */
static inline void end_linker(elfm_linker *l)
{
  elfm_error err;
  CHECK_OK(elfm_link_finish(l, &err), &err);
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) elfm_track_free(t);
  elfm_link_free(l);
}

#endif
