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

/* A bright detection (intensity 100) at (x, y, z) um with the sigmas of a
 * bright object's fit: 1 um laterally, 3 um in z (the encounter tests'). */
static inline elfm_detection link_test_det_bright(double x, double y, double z)
{
  elfm_detection d = link_test_det(x, y, z, 100);
  d.sigma_x_um = d.sigma_y_um = 1;
  d.sigma_z_um = 3;
  return d;
}

/* One frame f (at t_us) of two objects at p and q for the encounter tests:
 * seen apart, or merged into one spot, found twice 0.1 um apart at their
 * mean lateral position and z_merged, as a view fit finds a merged image. */
static inline void link_test_step_pair(elfm_linker *l, int64_t f, int64_t t_us, const double p[3],
                                       const double q[3], int merged, double z_merged)
{
  elfm_error err;
  elfm_detection d[2];
  if (merged) {
    const double x = 0.5 * (p[0] + q[0]), y = 0.5 * (p[1] + q[1]);
    d[0] = link_test_det_bright(x, y, z_merged);
    d[1] = link_test_det_bright(x + 0.1, y, z_merged);
  } else {
    d[0] = link_test_det_bright(p[0], p[1], p[2]);
    d[1] = link_test_det_bright(q[0], q[1], q[2]);
  }
  CHECK_OK(elfm_link_step(l, f, t_us, d, 2, &err), &err);
}

/* The track command's linking defaults for steps 6 and 7 (cli/
 * cmd_track_opts.c) on top of the library's: the linker metric's z / 1.5,
 * the swap review after 8 points, encounters within 5 um, 4 frames apart
 * within one, established tracks first. Circles and the reviews' ratios
 * are left to the test. */
static inline void link_test_review_options(elfm_link_options *o)
{
  elfm_link_options_default(o);
  o->kz = 1.5;
  o->swap_points = 8;
  o->encounter_um = 5;
  o->encounter_apart = 4;
  o->priority_points = 8;
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

/* test_link.c 5b's scene (the rescue; test_link_input.c 1b too): a bead
 * at 3 um/ms along x, dark for frames 30-39, back 15 um to the side of its
 * line at frame 40. The linker starts with the rescue
 * factor `factor`; just before frame 40 it is set to `at_return` (NaN: not
 * set; a refused value must be refused). Returns the tracks made. */
static inline int link_test_rescue_return(const elfm_link_options *o, double factor, double at_return)
{
  elfm_error err;
  elfm_link_options orr = *o;
  orr.rescue_gate_factor = factor;
  elfm_linker *l = elfm_link_create(&orr, &err);
  const int64_t T0 = 1000000000000LL;
  for (int f = 0; f < 60; f++) {
    if (f >= 30 && f < 40) { CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, NULL, 0, &err), &err); continue; }
    if (f == 40 && at_return >= 0) CHECK_OK(elfm_link_set_rescue_gate_factor(l, at_return, &err), &err);
    if (f == 40 && at_return < 0) CHECK(elfm_link_set_rescue_gate_factor(l, at_return, &err) == ELFM_ERR_INVALID);
    elfm_detection d = link_test_det(3.0 * f, f >= 40 ? 15.0 : 0.0, 5, 1);
    CHECK_OK(elfm_link_step(l, f, T0 + f * 1000, &d, 1, &err), &err);
  }
  CHECK_OK(elfm_link_finish(l, &err), &err);
  int n = 0;
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) { n++; elfm_track_free(t); }
  elfm_link_free(l);
  return n;
}

#endif
