/* calib_test_util.h — what the tests of fitted centres share: the
 * largest difference of two calibrations' centres once the two moves no
 * recording can show (elfm_calib.h: all views alike, and in proportion to
 * the disparities) are taken out. */
#ifndef ELFM_TESTS_CALIB_TEST_UTIL_H
#define ELFM_TESTS_CALIB_TEST_UTIL_H

#include <math.h>

#include "check.h"
#include "elfm_recon.h"

/* Remove from e[v] (one axis) its least-squares fit a + b d[v]: the moves
 * no recording can show (elfm_calib.h). */
static inline void gauge_free(int nv, const double *d, double *e)
{
  double n = nv, sd = 0, sdd = 0, se = 0, sde = 0;
  for (int v = 0; v < nv; v++) {
    sd += d[v];
    sdd += d[v] * d[v];
    se += e[v];
    sde += d[v] * e[v];
  }
  const double b = (n * sde - sd * se) / (n * sdd - sd * sd), a = (se - b * sd) / n;
  for (int v = 0; v < nv; v++) e[v] -= a + b * d[v];
}

/* Largest gauge-free difference of a's centres from b's, px; each view's
 * into per_view[v] (may be NULL). */
static inline double centre_errors(const elfm_calib *a, const elfm_calib *b, double *per_view)
{
  double eu[ELFM_MAX_VIEWS] = {0}, ew[ELFM_MAX_VIEWS] = {0}, du[ELFM_MAX_VIEWS] = {0},
         dw[ELFM_MAX_VIEWS] = {0};
  for (int v = 0; v < a->n_views; v++) {
    eu[v] = a->views[v].cx_px - b->views[v].cx_px;
    ew[v] = a->views[v].cy_px - b->views[v].cy_px;
    du[v] = b->views[v].dx_px_per_um;
    dw[v] = b->views[v].dy_px_per_um;
  }
  gauge_free(a->n_views, du, eu);
  gauge_free(a->n_views, dw, ew);
  double worst = 0;
  for (int v = 0; v < a->n_views; v++) {
    worst = fmax(worst, hypot(eu[v], ew[v]));
    if (per_view) per_view[v] = hypot(eu[v], ew[v]);
  }
  return worst;
}

static inline double centre_error(const elfm_calib *a, const elfm_calib *b)
{
  return centre_errors(a, b, NULL);
}

/* The paper's system on the EVK4 (elfm_optics_default, 1280 x 720, 4.86
 * um pixels) into *c; 0 when that failed (counted by CHECK_OK). */
static inline int calib_test_default(elfm_calib *c)
{
  elfm_optics op;
  elfm_error err;
  elfm_optics_default(&op);
  const elfm_status st = elfm_calib_from_optics(&op, 1280, 720, 4.86, c, &err);
  CHECK_OK(st, &err);
  return st == ELFM_OK;
}

#endif
