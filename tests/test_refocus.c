/* test_refocus.c — refocusing on synthetic Fourier LFM frames rendered with
 * the SPEC §2 projection at the paper's geometry:
 *  - a bead anywhere in +-90 um z and the field of view: the volume's peak is
 *    within one voxel laterally and one plane axially of the truth (both paths);
 *  - dense and sparse agree to 1e-4 of the maximum (with and without ghost rules);
 *    the sparse path's runs joined across gaps of zeros give the same bits as
 *    runs taken one by one;
 *    with the agreement rule they keep the same voxels (also with whole-pixel
 *    shifts, over a sequence of frames);
 *  - a uniform frame gives exactly 1 wherever views sample, although the outer
 *    views overhang the 720-row sensor (normalisation by sampling views);
 *  - ghost rules: agreement drops what few views see; thresholds;
 *  - bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lfm_render.h"
#include "elfm_recon.h"
#include "refocus_internal.h" /* the workspace's agree_portable and merge_gap_px */
#include "volume_test_util.h"

/* sigma 1.3 px: the 3.9 um lateral FWHM / 0.93 um/px / 2.355 */
static void render_bead(elfm_frame *f, const elfm_calib *c, double x, double y, double z,
                        double amp)
{
  render_views(f, c, x, y, z, amp, 1.3, 0, 0, 0);
}

/* n random pixels set to base + 0..199 (negative for half of them when
 * signed_values: cancelling samples), from the LCG state *s. */
static void add_noise(elfm_frame *f, uint32_t *s, int n, float base, int signed_values)
{
  for (int i = 0; i < n; i++) {
    *s = *s * 1664525u + 1013904223u;
    uint32_t pix = (*s >> 4) % (uint32_t)(f->w * f->h);
    *s = *s * 1664525u + 1013904223u;
    float a = base + (float)((*s >> 24) % 200);
    if (signed_values && ((*s >> 9) & 1)) a = -a;
    elfm_frame_set(f, pix, a);
  }
}

static size_t argmax(const elfm_volume *v)
{
  size_t n = (size_t)v->w * v->h * v->nz, best = 0;
  for (size_t i = 1; i < n; i++)
    if (v->data[i] > v->data[best]) best = i;
  return best;
}

static void paper_calib(elfm_calib *c)
{
  elfm_optics o;
  elfm_error err;
  elfm_optics_default(&o);
  CHECK_OK(elfm_calib_from_optics(&o, 1280, 720, 4.86, c, &err), &err);
}

static void test_bead_positions(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, NULL, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *vd = elfm_refocus_volume_create(p, &err), *vs = elfm_refocus_volume_create(p, &err);
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  const double fov_um = 0.5 * (c->view_w_px - 1) * c->um_per_px;
  uint32_t s = 7;
  int worst_lat = 0, worst_ax = 0;
  for (int trial = 0; trial < 14; trial++) {
    s = s * 1664525u + 1013904223u;
    double x = ((s >> 8) % 10001 / 10000.0 * 2 - 1) * (fov_um - 8);
    s = s * 1664525u + 1013904223u;
    double y = ((s >> 8) % 10001 / 10000.0 * 2 - 1) * (fov_um - 8);
    s = s * 1664525u + 1013904223u;
    double z = ((s >> 8) % 10001 / 10000.0 * 2 - 1) * 90.0;
    if (trial == 0) { x = 0; y = 0; z = 90; }
    if (trial == 1) { x = -fov_um + 8; y = fov_um - 8; z = -90; }
    elfm_frame_clear(f);
    render_bead(f, c, x, y, z, 255.0);
    f->t_us = 1000 + trial;
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, vd, ws, &err), &err);
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, vs, ws, &err), &err);
    CHECK_EQ_INT(vs->t_us, 1000 + trial);
    for (int path = 0; path < 2; path++) {
      const elfm_volume *v = path ? vs : vd;
      size_t i = argmax(v);
      int X = (int)(i % (size_t)v->w), Y = (int)(i / (size_t)v->w % (size_t)v->h);
      int k = (int)(i / ((size_t)v->w * v->h));
      double Xt = x / c->um_per_px + 0.5 * (v->w - 1), Yt = y / c->um_per_px + 0.5 * (v->h - 1);
      double kt = (z - c->z_min_um) / c->z_step_um;
      int lat = fabs(X - Xt) > fabs(Y - Yt) ? (int)ceil(fabs(X - Xt) - 1e-9) : (int)ceil(fabs(Y - Yt) - 1e-9);
      int ax = (int)ceil(fabs(k - kt) - 1e-9);
      if (lat > worst_lat) worst_lat = lat;
      if (ax > worst_ax) worst_ax = ax;
      CHECK_MSG(fabs(X - Xt) <= 1.0 && fabs(Y - Yt) <= 1.0 && fabs(k - kt) <= 1.0,
                "bead (%.1f, %.1f, %.1f) um: peak at voxel (%d, %d, %d), truth (%.2f, %.2f, %.2f), %s",
                x, y, z, X, Y, k, Xt, Yt, kt, path ? "sparse" : "dense");
    }
    float m = vmax(vd);
    CHECK_MSG(maxdiff(vd, vs) <= 1e-4f * m, "dense/sparse differ by %g of max %g", maxdiff(vd, vs), m);
  }
  printf("worst peak error: %d voxel(s) laterally, %d plane(s) axially\n", worst_lat, worst_ax);
  elfm_frame_free(f);
  elfm_volume_free(vd);
  elfm_volume_free(vs);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
}

/* Random time-surface-like frames (noise and beads) with each ghost rule:
 * dense and sparse agree; a sparse call after a dense one (and on a fresh
 * volume) starts from a clean volume. */
static void test_dense_sparse_agree(const elfm_calib *c, int check_auto)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  for (int mode = 0; mode < 4; mode++) {
    elfm_refocus_options o;
    elfm_refocus_options_default(&o);
    o.agree_frac = 0.0;
    if (mode == 1) o.agree_frac = 0.6;
    if (mode == 2) { o.threshold = ELFM_GHOST_THR_FRAC_MAX; o.threshold_value = 0.3; }
    if (mode == 3) { o.threshold = ELFM_GHOST_THR_MAD; o.threshold_value = 3; o.agree_frac = 0.3; }
    elfm_refocus_plan *p = NULL;
    CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
    elfm_refocus_workspace *wd = NULL, *wsp = NULL;
    CHECK_OK(elfm_refocus_workspace_create(p, &wd, &err), &err);
    CHECK_OK(elfm_refocus_workspace_create(p, &wsp, &err), &err);
    elfm_volume *vd = elfm_refocus_volume_create(p, &err), *vs = elfm_refocus_volume_create(p, &err);
    uint32_t s = 1234u + (uint32_t)mode;
    for (int rep = 0; rep < 2; rep++) {
      elfm_frame_clear(f);
      add_noise(f, &s, 3000, 20.0f, 0);
      for (int b = 0; b < 5; b++)
        render_bead(f, c, -50.0 + 25 * b, 40.0 - 20 * b, -80.0 + 40 * b + rep, 200.0);
      /* a busy row (listed right to left, across view boxes): the sparse
       * path's row sort on more than a handful of pixels */
      for (int x = 1000; x > 300; x -= 1 + (x % 3 == 0))
        elfm_frame_set(f, (uint32_t)(360 * f->w + x), (float)(1 + x % 97));
      CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, vd, wd, &err), &err);
      if (rep == 1) /* reuse a volume the dense path filled: must be cleared */
        CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, vs, wsp, &err), &err);
      CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, vs, wsp, &err), &err);
      CHECK(elfm_refocus_workspace_last_path(wsp) == ELFM_PATH_SPARSE);
      float m = vmax(vd), d = maxdiff(vd, vs);
      CHECK(m > 0.0f);
      CHECK_MSG(d <= 1e-4f * m, "mode %d rep %d: dense/sparse differ by %g (max %g)", mode, rep, d, m);
    }
    /* auto: a 3000-pixel frame is sparse at the paper's geometry (with
     * fewer, smaller views the dense path may be the cheaper) */
    CHECK_OK(elfm_refocus_execute(p, f, vs, wsp, &err), &err);
    if (check_auto) CHECK(elfm_refocus_workspace_last_path(wsp) == ELFM_PATH_SPARSE);
    elfm_volume_free(vd);
    elfm_volume_free(vs);
    elfm_refocus_workspace_free(wd);
    elfm_refocus_workspace_free(wsp);
    elfm_refocus_plan_free(p);
  }
  elfm_frame_free(f);
}

/* The sparse path's agreement rule (support maps, candidates, gather) keeps
 * exactly the voxels the dense path keeps: on non-negative frames the same
 * voxels are non-zero (a superset of candidates that was too small, or a
 * count taken on the wrong views, would drop or add voxels) and the values
 * agree; signed frames (cancelling samples) agree to 1e-4 of the maximum.
 * Checked with the paper's views and with views moved so that every plane's
 * shift is a whole pixel (bilinear weights 0 and 1: the taps of weight 0
 * must not count), for 1 view, 30 % and all views, over a sequence of
 * frames through one workspace and volume (rows cleared between frames).
 * portable: the sparse workspace runs the portable agreement code (the one
 * used on CPUs without AVX2), which must give the same result. */
static void test_agree_exact(const elfm_calib *c0, int portable)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c0->sensor_width_px, c0->sensor_height_px, &err);
  for (int geo = 0; geo < 2; geo++) {
    elfm_calib c = *c0;
    if (geo == 1)
      for (int v = 0; v < c.n_views; v++) {
        /* z_k dx = whole pixels on every plane, cx - (W-1)/2 whole */
        c.views[v].dx_px_per_um = round(c.views[v].dx_px_per_um * c.z_step_um) / c.z_step_um;
        c.views[v].dy_px_per_um = round(c.views[v].dy_px_per_um * c.z_step_um) / c.z_step_um;
        c.views[v].cx_px = floor(c.views[v].cx_px) + 0.5 * ((c.view_w_px - 1) % 2);
        c.views[v].cy_px = floor(c.views[v].cy_px) + 0.5 * ((c.view_h_px - 1) % 2);
      }
    const double fracs[3] = {0.01, 0.3, 1.0};
    for (int fi = 0; fi < 3; fi++) {
      elfm_refocus_options o;
      elfm_refocus_options_default(&o);
      o.agree_frac = fracs[fi];
      elfm_refocus_plan *p = NULL;
      CHECK_OK(elfm_refocus_plan_create(&c, &o, &p, &err), &err);
      elfm_refocus_workspace *wd = NULL, *wsp = NULL;
      CHECK_OK(elfm_refocus_workspace_create(p, &wd, &err), &err);
      CHECK_OK(elfm_refocus_workspace_create(p, &wsp, &err), &err);
      wsp->agree_portable = portable;
      elfm_volume *vd = elfm_refocus_volume_create(p, &err), *vs = elfm_refocus_volume_create(p, &err);
      const size_t nvox = (size_t)vd->w * vd->h * vd->nz;
      uint32_t s = 99u + 7u * (uint32_t)(geo * 3 + fi);
      size_t kept_total = 0;
      for (int rep = 0; rep < 4; rep++) {
        const int signed_frame = rep == 3;
        elfm_frame_clear(f);
        add_noise(f, &s, 2000, 1.0f, signed_frame);
        for (int b = 0; b < 6; b++)
          render_bead(f, &c, -60.0 + 23 * b + 3 * rep, 50.0 - 19 * b, -85.0 + 33 * b + 2 * rep,
                      signed_frame && b % 2 ? -150.0 : 150.0);
        CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, vd, wd, &err), &err);
        CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, vs, wsp, &err), &err);
        float m = vmax(vd), d = maxdiff(vd, vs);
        CHECK(m > 0.0f);
        CHECK_MSG(d <= 1e-4f * m, "%s geo %d agree %g rep %d: dense/sparse differ by %g (max %g)",
                  portable ? "portable" : "default", geo, fracs[fi], rep, d, m);
        if (!signed_frame) {
          size_t mismatch = 0, kept = 0;
          for (size_t i = 0; i < nvox; i++) {
            mismatch += (vd->data[i] != 0.0f) != (vs->data[i] != 0.0f);
            kept += vd->data[i] != 0.0f;
          }
          CHECK_MSG(mismatch == 0, "%s geo %d agree %g rep %d: %zu voxels kept by one path only",
                    portable ? "portable" : "default", geo, fracs[fi], rep, mismatch);
          kept_total += kept;
        }
      }
      /* the rule keeps something on these frames */
      CHECK_MSG(kept_total > 0, "geo %d agree %g: nothing kept", geo, fracs[fi]);
      elfm_volume_free(vd);
      elfm_volume_free(vs);
      elfm_refocus_workspace_free(wd);
      elfm_refocus_workspace_free(wsp);
      elfm_refocus_plan_free(p);
    }
  }
  elfm_frame_free(f);
}

/* The sparse path joins a view row's runs across gaps of up to
 * ELFM_REFOCUS_MERGE_GAP_PX zeros (refocus_internal.h): the same floats,
 * voxel for voxel, as the runs scattered one by one, on frames whose rows
 * hold clusters 1..40 px apart (around the limit), across view boxes, signed
 * values (the integral) and beads, over a sequence of frames through one
 * workspace each; and the same as the dense path within 1e-4 of the
 * maximum. It must have joined runs, or it tests nothing. */
static void test_sparse_runs_joined(const elfm_calib *c)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  o.agree_frac = 0.0;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  elfm_refocus_workspace *wj = NULL, *w1 = NULL, *wd = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &wj, &err), &err);
  CHECK_OK(elfm_refocus_workspace_create(p, &w1, &err), &err);
  CHECK_OK(elfm_refocus_workspace_create(p, &wd, &err), &err);
  CHECK(wj->merge_gap_px == ELFM_REFOCUS_MERGE_GAP_PX && ELFM_REFOCUS_MERGE_GAP_PX > 0);
  w1->merge_gap_px = 0;
  elfm_volume *vj = elfm_refocus_volume_create(p, &err), *v1 = elfm_refocus_volume_create(p, &err);
  elfm_volume *vd = elfm_refocus_volume_create(p, &err);
  const size_t nvox = (size_t)vj->w * vj->h * vj->nz;
  uint32_t s = 777u;
  for (int rep = 0; rep < 4; rep++) {
    elfm_frame_clear(f);
    add_noise(f, &s, 2000, 1.0f, rep & 1);
    for (int b = 0; b < 6; b++)
      render_bead(f, c, -60.0 + 22 * b, 50.0 - 17 * b + rep, -85.0 + 33 * b, 150.0);
    /* rows of clusters of 1-4 pixels, gaps 1..40 px, across the sensor */
    for (int r = 0; r < 12; r++) {
      const int y = 30 + 55 * r + rep;
      int x = 5 + 3 * r;
      for (int g = 1; x < c->sensor_width_px - 5; g = g % 40 + 1) {
        const int len = 1 + (x + r) % 4;
        for (int i = 0; i < len && x < c->sensor_width_px; i++, x++) {
          float a = (float)(1 + (x * 7 + y) % 89);
          if ((rep & 1) && (x + y) % 3 == 0) a = -a;
          elfm_frame_set(f, (uint32_t)(y * f->w + x), a);
        }
        x += g;
      }
    }
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, vj, wj, &err), &err);
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, v1, w1, &err), &err);
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, vd, wd, &err), &err);
    CHECK_MSG(wj->n_runs < w1->n_runs, "rep %d: %zu joined runs, %zu single", rep, wj->n_runs, w1->n_runs);
    size_t differ = 0;
    for (size_t i = 0; i < nvox; i++) differ += memcmp(&vj->data[i], &v1->data[i], sizeof(float)) != 0;
    CHECK_MSG(differ == 0, "rep %d: %zu voxels differ between joined and single runs", rep, differ);
    float m = vmax(vd), d = maxdiff(vd, vj);
    CHECK(m > 0.0f);
    CHECK_MSG(d <= 1e-4f * m, "rep %d: dense/joined sparse differ by %g (max %g)", rep, d, m);
  }
  elfm_volume_free(vj);
  elfm_volume_free(v1);
  elfm_volume_free(vd);
  elfm_refocus_workspace_free(wj);
  elfm_refocus_workspace_free(w1);
  elfm_refocus_workspace_free(wd);
  elfm_refocus_plan_free(p);
  elfm_frame_free(f);
}

/* The portable agreement code and the default one (AVX2 where the CPU has
 * it) give the same floats, voxel for voxel, on a busy frame (beads,
 * noise, a dense row), over a sequence of frames through one workspace. */
static void test_agree_portable_same(const elfm_calib *c)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  elfm_refocus_workspace *wa = NULL, *wb = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &wa, &err), &err);
  CHECK_OK(elfm_refocus_workspace_create(p, &wb, &err), &err);
  wb->agree_portable = 1;
  elfm_volume *va = elfm_refocus_volume_create(p, &err), *vb = elfm_refocus_volume_create(p, &err);
  const size_t nvox = (size_t)va->w * va->h * va->nz;
  uint32_t s = 4242u;
  size_t kept = 0;
  for (int rep = 0; rep < 3; rep++) {
    elfm_frame_clear(f);
    add_noise(f, &s, 4000, 1.0f, 0);
    for (int b = 0; b < 12; b++)
      render_bead(f, c, -70.0 + 13 * b + rep, 60.0 - 11 * b, -88.0 + 16 * b + 3 * rep, 180.0);
    for (int x = 200; x < 1100; x += 1 + x % 2)
      elfm_frame_set(f, (uint32_t)(300 * f->w + x), (float)(1 + x % 53));
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, va, wa, &err), &err);
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, f, vb, wb, &err), &err);
    size_t differ = 0;
    for (size_t i = 0; i < nvox; i++) {
      differ += memcmp(&va->data[i], &vb->data[i], sizeof(float)) != 0;
      kept += va->data[i] != 0.0f;
    }
    CHECK_MSG(differ == 0, "rep %d: %zu voxels differ between portable and default", rep, differ);
  }
  CHECK(kept > 0);
  elfm_volume_free(va);
  elfm_volume_free(vb);
  elfm_refocus_workspace_free(wa);
  elfm_refocus_workspace_free(wb);
  elfm_refocus_plan_free(p);
  elfm_frame_free(f);
}

static void test_uniform_overhang(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, NULL, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *v = elfm_refocus_volume_create(p, &err);
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  for (uint32_t i = 0; i < (uint32_t)(f->w * f->h); i++) {
    f->data[i] = 1.0f;
    f->idx[i] = i;
  }
  f->nnz = (size_t)f->w * f->h;
  CHECK_OK(elfm_refocus_execute(p, f, v, ws, &err), &err);
  CHECK(elfm_refocus_workspace_last_path(ws) == ELFM_PATH_DENSE);
  int min_views = 1000, max_views = 0, bad = 0;
  for (int k = 0; k < v->nz; k++)
    for (int Y = 0; Y < v->h; Y++)
      for (int X = 0; X < v->w; X++) {
        int n = elfm_refocus_plan_views_at(p, X, Y, k);
        float a = v->data[((size_t)k * v->h + Y) * v->w + X];
        if (n < min_views) min_views = n;
        if (n > max_views) max_views = n;
        if (n > 0 ? fabsf(a - 1.0f) > 1e-5f : a != 0.0f) bad++;
      }
  CHECK_EQ_INT(bad, 0);
  CHECK_EQ_INT(max_views, c->n_views);
  CHECK(min_views < c->n_views); /* the outer rows overhang the sensor */
  printf("views per voxel: %d..%d of %d\n", min_views, max_views, c->n_views);
  elfm_frame_free(f);
  elfm_volume_free(v);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
}

static void test_ghost_rules(const elfm_calib *c)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  /* a spot in 3 views only: some voxels get signal from 3 views */
  elfm_calib c3 = *c;
  elfm_frame_clear(f);
  for (int v = 0; v < 3; v++) {
    double u, w;
    elfm_calib_project(&c3, v + 10, 5.0, 5.0, 0.0, &u, &w);
    elfm_frame_set(f, (uint32_t)((int)w * f->w + (int)u), 100.0f);
  }
  for (int mode = 0; mode < 3; mode++) {
    elfm_refocus_options o;
    elfm_refocus_options_default(&o);
    o.agree_frac = 0.0;
    if (mode == 1) o.agree_frac = 0.5;
    if (mode == 2) { o.threshold = ELFM_GHOST_THR_ABS; o.threshold_value = 1e6; }
    elfm_refocus_plan *p = NULL;
    CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
    elfm_refocus_workspace *ws = NULL;
    CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
    elfm_volume *v = elfm_refocus_volume_create(p, &err);
    for (int path = ELFM_PATH_DENSE; path <= ELFM_PATH_SPARSE; path++) {
      CHECK_OK(elfm_refocus_execute_path(p, (elfm_refocus_path)path, f, v, ws, &err), &err);
      float m = vmax(v);
      if (mode == 0) CHECK(m > 1.0f);
      else CHECK_MSG(m == 0.0f, "mode %d path %d: max %g", mode, path, m);
    }
    elfm_volume_free(v);
    elfm_refocus_workspace_free(ws);
    elfm_refocus_plan_free(p);
  }
  /* FRAC_MAX keeps the bead's peak, removes voxels under 0.5 x max */
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  o.threshold = ELFM_GHOST_THR_FRAC_MAX;
  o.threshold_value = 0.5;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *v = elfm_refocus_volume_create(p, &err);
  elfm_frame_clear(f);
  render_bead(f, c, 10, -10, 30, 255);
  CHECK_OK(elfm_refocus_execute(p, f, v, ws, &err), &err);
  float m = vmax(v);
  size_t nz = 0, low = 0;
  for (size_t i = 0; i < (size_t)v->w * v->h * v->nz; i++) {
    nz += v->data[i] != 0.0f;
    low += v->data[i] != 0.0f && v->data[i] < 0.5f * m;
  }
  CHECK(m > 100.0f);
  CHECK(nz > 0 && low == 0);
  elfm_volume_free(v);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
  elfm_frame_free(f);
}

static void test_bad_input(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_plan *p = NULL;
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  o.agree_frac = 1.5;
  CHECK(elfm_refocus_plan_create(c, &o, &p, &err) == ELFM_ERR_INVALID && p == NULL);
  elfm_refocus_options_default(&o);
  o.threshold = ELFM_GHOST_THR_MAD;
  o.threshold_value = NAN;
  CHECK(elfm_refocus_plan_create(c, &o, &p, &err) == ELFM_ERR_INVALID);
  elfm_calib bad = *c;
  bad.z_step_um = 0;
  CHECK(elfm_refocus_plan_create(&bad, NULL, &p, &err) == ELFM_ERR_INVALID);
  bad = *c;
  bad.views[3].cx_px = NAN;
  CHECK(elfm_refocus_plan_create(&bad, NULL, &p, &err) == ELFM_ERR_INVALID);
  bad = *c;
  bad.n_views = 0;
  CHECK(elfm_refocus_plan_create(&bad, NULL, &p, &err) == ELFM_ERR_INVALID);
  CHECK_OK(elfm_refocus_plan_create(c, NULL, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *v = elfm_refocus_volume_create(p, &err);
  elfm_frame *small = elfm_frame_create(640, 480, &err);
  CHECK(elfm_refocus_execute(p, small, v, ws, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "640") != NULL);
  elfm_volume *wrong = elfm_volume_create(10, 10, 10, 1, 0, 1, &err);
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  CHECK(elfm_refocus_execute(p, f, wrong, ws, &err) == ELFM_ERR_INVALID);
  elfm_volume_free(wrong);
  elfm_volume_free(v);
  elfm_frame_free(small);
  elfm_frame_free(f);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_workspace_free(NULL);
  elfm_refocus_plan_free(p);
  elfm_refocus_plan_free(NULL);
}

/* View support: at a bead's voxel every view that samples it sees signal;
 * at the voxel where two beads' images cross in a few views (a ghost of
 * the pair: shift-and-add at a plane between them), only a few do; outside
 * the volume 0. Checked against the volume: the support is the number of
 * non-zero samples the dense path averaged (with agreement 1.0 the voxel
 * survives exactly when support == views sampling). */
static void test_view_support(const elfm_calib *c)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  render_bead(f, c, 10.0, -12.0, 30.0, 200.0);
  render_bead(f, c, -25.0, 20.0, -40.0, 200.0);
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  o.agree_frac = 0.0;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *v = elfm_refocus_volume_create(p, &err);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, v, ws, &err), &err);
  /* the bead voxel: the volume's maximum */
  size_t i = argmax(v);
  int X = (int)(i % (size_t)v->w), Y = (int)(i / (size_t)v->w % (size_t)v->h);
  int k = (int)(i / ((size_t)v->w * v->h));
  int ns = -1;
  int n = elfm_refocus_view_support(p, f, X, Y, k, &ns);
  CHECK_EQ_INT(ns, elfm_refocus_plan_views_at(p, X, Y, k));
  CHECK_MSG(ns >= 20 && n == ns, "bead voxel: %d of %d views", n, ns);
  /* every other non-zero voxel of the volume: a bead's neighbourhood or a
   * ghost; count those with support below half their views */
  size_t low = 0, nz = 0, total = (size_t)v->w * v->h * v->nz, n_value_off = 0;
  int max_low = 0;
  for (size_t j = 0; j < total; j++) {
    if (v->data[j] == 0.0f) continue;
    int x = (int)(j % (size_t)v->w), y = (int)(j / (size_t)v->w % (size_t)v->h);
    int kk = (int)(j / ((size_t)v->w * v->h));
    int m = 0, a = elfm_refocus_view_support(p, f, x, y, kk, &m);
    CHECK(a >= 1 && a <= m);
    /* the value a fill reads from a kept frame is the volume's (float
     * sums there, double here) */
    double val = elfm_refocus_value_at(p, f, x, y, kk);
    if (!(fabs(val - v->data[j]) <= 1e-4 * fabs(v->data[j]) + 1e-4)) n_value_off++;
    nz++;
    if (2 * a < m) {
      low++;
      if (v->data[j] > (float)max_low) max_low = (int)v->data[j];
    }
  }
  CHECK_MSG(n_value_off == 0, "%zu of %zu voxels' value_at differs from the volume", n_value_off, nz);
  CHECK(elfm_refocus_value_at(p, f, -1, Y, k) == 0 && elfm_refocus_value_at(p, f, X, Y, v->nz) == 0);
  /* most non-zero voxels are seen by a few views only (ghosts, tails) */
  CHECK_MSG(low > nz / 2, "%zu of %zu non-zero voxels with low support", low, nz);
  /* zero voxels and voxels outside the volume have no support */
  size_t zi = 0;
  while (zi < total && v->data[zi] != 0.0f) zi++;
  CHECK(zi < total);
  CHECK_EQ_INT(elfm_refocus_view_support(p, f, (int)(zi % (size_t)v->w),
                                         (int)(zi / (size_t)v->w % (size_t)v->h),
                                         (int)(zi / ((size_t)v->w * v->h)), NULL), 0);
  ns = 7;
  CHECK_EQ_INT(elfm_refocus_view_support(p, f, -1, Y, k, &ns), 0);
  CHECK_EQ_INT(ns, 0);
  CHECK_EQ_INT(elfm_refocus_view_support(p, f, X, Y, v->nz, NULL), 0);
  elfm_volume_free(v);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
  elfm_frame_free(f);
}

/* The views' occupancy (elfm_refocus_occupancy): 0 for an empty frame, 1
 * for a frame non-zero everywhere (each box's pixels over the boxes' area);
 * a pixel at a view's centre adds 1 / box area, two such pixels twice
 * that; a pixel outside every box (the sensor's corner, left of and above
 * the first view's box), or listed with the value 0, adds nothing; a frame
 * of another size reads 0. */
static void fill_frame(elfm_frame *f) /* every pixel 1, listed once */
{
  f->nnz = (size_t)f->w * (size_t)f->h;
  for (size_t i = 0; i < f->nnz; i++) {
    f->data[i] = 1.0f;
    f->idx[i] = (uint32_t)i;
  }
}

static void test_occupancy(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  const int W = c->sensor_width_px, H = c->sensor_height_px;
  elfm_frame *f = elfm_frame_create(W, H, &err);
  CHECK(elfm_refocus_occupancy(p, f) == 0.0);
  fill_frame(f);
  CHECK_MSG(fabs(elfm_refocus_occupancy(p, f) - 1.0) < 1e-12, "full frame: %g",
            elfm_refocus_occupancy(p, f));
  elfm_frame_clear(f);
  const elfm_view *v0 = &c->views[0], *v1 = &c->views[1];
  const uint32_t a = (uint32_t)lround(v0->cy_px) * (uint32_t)W + (uint32_t)lround(v0->cx_px);
  const uint32_t b = (uint32_t)lround(v1->cy_px) * (uint32_t)W + (uint32_t)lround(v1->cx_px);
  elfm_frame_set(f, a, 3.0f);
  const double one = elfm_refocus_occupancy(p, f);
  CHECK_MSG(one > 0 && one < 1e-4, "one pixel: %g", one);
  elfm_frame_set(f, b, 0.5f);
  CHECK_MSG(fabs(elfm_refocus_occupancy(p, f) - 2 * one) < 1e-15, "two pixels: %g against 2 x %g",
            elfm_refocus_occupancy(p, f), one);
  elfm_frame_set(f, 0, 7.0f);        /* the corner */
  elfm_frame_set(f, a + 1, 0.0f);    /* listed, zero */
  CHECK_MSG(fabs(elfm_refocus_occupancy(p, f) - 2 * one) < 1e-15, "corner and zero: %g",
            elfm_refocus_occupancy(p, f));
  elfm_frame *g = elfm_frame_create(W / 2, H, &err);
  fill_frame(g);
  CHECK(elfm_refocus_occupancy(p, g) == 0.0);
  elfm_frame_free(g);
  elfm_frame_free(f);
  elfm_refocus_plan_free(p);
}

/* The voxel nearest (x, y, z) um and its position in voxels (fractional). */
static void voxel_of(const elfm_refocus_plan *p, const elfm_calib *c, double x, double y,
                     double z, int ijk[3], double pos[3])
{
  int w, h, nz;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  pos[0] = x / c->um_per_px + 0.5 * (w - 1);
  pos[1] = y / c->um_per_px + 0.5 * (h - 1);
  pos[2] = (z - c->z_min_um) / c->z_step_um;
  for (int a = 0; a < 3; a++) ijk[a] = (int)lround(pos[a]);
}

/* Views a brighter object's images explain (the ghost test of `track`):
 *  - frame 1, a bright bead S alone (wide images, sigma 2 px): at every
 *    voxel with signal, with S given and r_px beyond its images' reach,
 *    every view with signal is explained (n_explained == the plain view
 *    support, none left), and with no object given none is; the bead's own
 *    voxel is explained in every view too (an object never keeps itself);
 *  - frame 2, S and a dimmer bead B at S's depth 8.6 px to its side: B's
 *    views are all its own (none explained);
 *  - frame 3, S and B 20 um shallower, placed so that one column of views
 *    puts their images together: only a few of B's views are explained,
 *    fewer than half, and the rest pass a 0.3 support test;
 *  - others at fractional voxels: the shift between planes is linear, so a
 *    point between planes is placed as the calibration projects it. */
static void test_view_support_unexplained(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_options o;
  elfm_refocus_options_default(&o);
  o.agree_frac = 0.0;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &o, &p, &err), &err);
  int w, h, nz;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  const double xs = 10.0, ys = -12.0, zs = 30.0, sig = 2.0, amp = 255.0;
  /* the images' reach: values >= 1 within sig sqrt(2 ln amp), plus the
   * bilinear taps' diagonal */
  const double reach = sig * sqrt(2.0 * log(amp)) + 1.5;
  int S[3];
  double Sp[3];
  voxel_of(p, c, xs, ys, zs, S, Sp);
  const double others1[1][3] = {{Sp[0], Sp[1], Sp[2]}};

  elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  render_views(f, c, xs, ys, zs, amp, sig, 0, 0, 0);
  size_t n_signal = 0, n_all_explained = 0;
  for (int k = 0; k < nz; k += 3)
    for (int y = 0; y < h; y += 2)
      for (int x = 0; x < w; x += 2) {
        int ns = 0, ns2 = 0, ne = -1, ne0 = -1;
        const int n = elfm_refocus_view_support(p, f, x, y, k, &ns);
        if (n == 0) continue;
        n_signal++;
        const int nu = elfm_refocus_view_support_unexplained(p, f, x, y, k, others1, 1, reach,
                                                             &ns2, &ne);
        CHECK_EQ_INT(ns2, ns);
        n_all_explained += nu == 0 && ne == n;
        CHECK_EQ_INT(elfm_refocus_view_support_unexplained(p, f, x, y, k, others1, 0, reach,
                                                           NULL, &ne0),
                     n);
        CHECK_EQ_INT(ne0, 0);
      }
  CHECK_MSG(n_signal > 1000 && n_all_explained == n_signal,
            "bead alone: %zu of %zu voxels with signal explained in every view", n_all_explained,
            n_signal);
  int ns = 0, ne = 0;
  CHECK_EQ_INT(elfm_refocus_view_support_unexplained(p, f, S[0], S[1], S[2], others1, 1, reach,
                                                     &ns, &ne),
               0);
  CHECK_MSG(ns >= 20 && ne == ns, "bead voxel: %d of %d views explained", ne, ns);

  /* frame 2: B beside S at its depth, 8.6 px away in every view */
  elfm_frame_clear(f);
  const double xb = xs + 8.6 * c->um_per_px;
  render_views(f, c, xs, ys, zs, amp, sig, 0, 0, 0);
  render_views(f, c, xb, ys, zs, 120.0, 1.3, 0, 0, 0);
  int B[3];
  double Bp[3];
  voxel_of(p, c, xb, ys, zs, B, Bp);
  const int nb = elfm_refocus_view_support(p, f, B[0], B[1], B[2], &ns);
  CHECK_MSG(nb >= 20, "bead beside: support %d of %d", nb, ns);
  CHECK_EQ_INT(elfm_refocus_view_support_unexplained(p, f, B[0], B[1], B[2], others1, 1, 4.0,
                                                     NULL, &ne),
               nb);
  CHECK_EQ_INT(ne, 0);

  /* frame 3: B 20 um shallower where the views of S's column i = +2 see
   * the two together (the shift of view 14, i = +2, j = 0, carries B onto
   * S there) */
  elfm_frame_clear(f);
  const double dz = -20.0, zb = zs + dz;
  double u14s, w14s, u14b, w14b;
  elfm_calib_project(c, 14, xs, ys, zs, &u14s, &w14s);
  elfm_calib_project(c, 14, xs, ys, zb, &u14b, &w14b);
  const double xb3 = xs + (u14s - u14b) * c->um_per_px;
  render_views(f, c, xs, ys, zs, amp, sig, 0, 0, 0);
  render_views(f, c, xb3, ys, zb, 120.0, 1.3, 0, 0, 0);
  voxel_of(p, c, xb3, ys, zb, B, Bp);
  const int n3 = elfm_refocus_view_support(p, f, B[0], B[1], B[2], &ns);
  const int nu3 =
      elfm_refocus_view_support_unexplained(p, f, B[0], B[1], B[2], others1, 1, 4.0, NULL, &ne);
  CHECK_MSG(ne >= 1 && 2 * ne < n3 && nu3 + ne == n3 && nu3 >= 0.3 * ns,
            "bead 20 um above: %d of %d views explained, %d left of %d sampling", ne, n3, nu3, ns);

  /* between planes: an object half a plane below S's voxel, moved
   * sideways so that view 14 (i = +2, j = 0) puts its image on the voxel's
   * sample point there, as the calibration projects it. With r 0.05 px
   * that view alone is explained: the nearest plane's shift would miss by
   * half a plane's (0.34 px), view 13 (i = +1) by half of that. */
  elfm_frame_clear(f);
  render_views(f, c, xs, ys, zs, amp, sig, 0, 0, 0);
  const double xv = (S[0] - 0.5 * (w - 1)) * c->um_per_px;
  const double yv = (S[1] - 0.5 * (h - 1)) * c->um_per_px;
  const double zk = c->z_min_um + S[2] * c->z_step_um, zh = zk + 0.5 * c->z_step_um;
  double uk, wk, uh, wh;
  elfm_calib_project(c, 14, xv, yv, zk, &uk, &wk);
  elfm_calib_project(c, 14, xv, yv, zh, &uh, &wh);
  const double othersf[1][3] = {{S[0] + (uk - uh), S[1], S[2] + 0.5}};
  const int nf = elfm_refocus_view_support(p, f, S[0], S[1], S[2], NULL);
  const int nuf = elfm_refocus_view_support_unexplained(p, f, S[0], S[1], S[2], othersf, 1, 0.05,
                                                        NULL, &ne);
  CHECK_MSG(fabs(uk - uh) > 0.2 && ne == 1 && nuf == nf - 1,
            "half a plane below, moved %.3f px: %d views explained", uk - uh, ne);
  elfm_frame_free(f);
  elfm_refocus_plan_free(p);
}

/* Another geometry for the sparse agreement code, which packs a row of W
 * voxels into 64-bit words and 256-bit registers (one load per window when
 * W <= 192, two above; two 256-voxel chunks above 256): the central 3 x 3
 * views of the paper's 5 x 5 (9 views, a 3 x 3 Fourier LFM) with crop boxes
 * of w x h px, which may overlap and overhang the sensor. */
static void other_geometry(const elfm_calib *c, int w, int h, int central3x3, elfm_calib *out)
{
  *out = *c;
  out->view_w_px = w;
  out->view_h_px = h;
  if (central3x3) {
    const int keep[9] = {6, 7, 8, 11, 12, 13, 16, 17, 18};
    for (int i = 0; i < 9; i++) out->views[i] = c->views[keep[i]];
    out->n_views = 9;
  }
}

int main(void)
{
  elfm_calib c;
  paper_calib(&c);
  CHECK_EQ_INT(c.n_views, 25);
  test_bead_positions(&c);
  test_dense_sparse_agree(&c, 1);
  test_sparse_runs_joined(&c);
  test_agree_exact(&c, 0);
  test_agree_exact(&c, 1);
  test_agree_portable_same(&c);
  /* other widths (one chunk of two loads; two chunks) and view counts */
  const int geos[3][3] = {{200, 120, 1}, {300, 64, 0}, {61, 150, 1}};
  for (int g = 0; g < 3; g++) {
    elfm_calib o;
    other_geometry(&c, geos[g][0], geos[g][1], geos[g][2], &o);
    test_agree_exact(&o, 0);        /* default == dense */
    test_agree_portable_same(&o);   /* portable == default, bit for bit */
    /* the plain sparse path streams blocks of rows into the volume: an odd
     * width (61) starts every other plane off a 16-byte line and ends its
     * last block of rows between groups of four floats */
    test_dense_sparse_agree(&o, 0);
  }
  test_uniform_overhang(&c);
  test_ghost_rules(&c);
  test_view_support(&c);
  test_view_support_unexplained(&c);
  test_occupancy(&c);
  test_bad_input(&c);
  return check_report();
}
