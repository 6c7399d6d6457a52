/* calib_test_util.h — what the tests of fitted centres share: centres
 * moved by a seeded pattern free of the two moves no recording can show
 * (elfm_calib.h: all views alike, and in proportion to the disparities),
 * the largest difference of two calibrations' centres once those moves are
 * taken out, and the paper's calibration. */
#ifndef ELFM_TESTS_CALIB_TEST_UTIL_H
#define ELFM_TESTS_CALIB_TEST_UTIL_H

#include <math.h>
#include <stdint.h>

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

/* A seeded uniform draw in [0, 1] (5 decimals) */
static inline double lcg(uint32_t *s)
{
  *s = *s * 1664525u + 1013904223u;
  return (*s >> 8) % 100001 / 100000.0;
}

/* *c moved by a gauge-free pattern of about `rms_px` per axis (seeded). */
static inline void perturb(elfm_calib *c, double rms_px, uint32_t seed)
{
  double eu[ELFM_MAX_VIEWS] = {0}, ew[ELFM_MAX_VIEWS] = {0}, du[ELFM_MAX_VIEWS] = {0},
         dw[ELFM_MAX_VIEWS] = {0};
  for (int v = 0; v < c->n_views; v++) {
    eu[v] = rms_px * 1.7 * (2 * lcg(&seed) - 1); /* uniform: sd = 1.7 / sqrt 3 ~ 1 x rms */
    ew[v] = rms_px * 1.7 * (2 * lcg(&seed) - 1);
    du[v] = c->views[v].dx_px_per_um;
    dw[v] = c->views[v].dy_px_per_um;
  }
  gauge_free(c->n_views, du, eu);
  gauge_free(c->n_views, dw, ew);
  for (int v = 0; v < c->n_views; v++) {
    c->views[v].cx_px += eu[v];
    c->views[v].cy_px += ew[v];
  }
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

/* The central view (i = j = 0), -1 when there is none */
static inline int centre_view(const elfm_calib *c)
{
  for (int v = 0; v < c->n_views; v++)
    if (c->views[v].i == 0 && c->views[v].j == 0) return v;
  return -1;
}

/* value into pixel (x, y) of a frame drawn by hand, listed (the frame's
 * list is what the sweep's spots read) */
static inline void frame_put(elfm_frame *f, long x, long y, float value)
{
  if (x < 0 || y < 0 || x >= f->w || y >= f->h) return;
  const size_t i = (size_t)y * (size_t)f->w + (size_t)x;
  if (f->data[i] == 0) f->idx[f->nnz++] = (uint32_t)i;
  f->data[i] += value;
}

/* a Gaussian spot (sigma 1 px, peak `peak`) centred at (u, w) */
static inline void frame_spot(elfm_frame *f, double u, double w, double peak)
{
  for (long y = lround(w) - 3; y <= lround(w) + 3; y++)
    for (long x = lround(u) - 3; x <= lround(u) + 3; x++)
      frame_put(f, x, y, (float)(peak * exp(-0.5 * ((x - u) * (x - u) + (y - w) * (y - w)))));
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
