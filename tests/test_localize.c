/* test_localize.c — elfm_refocus_localize, the view fit (recon/localize.c),
 * on synthetic Fourier LFM frames rendered with the SPEC §2 projection at
 * the paper's geometry:
 *  - a bead anywhere in +-80 um z and the field of view, started 1 voxel and
 *    2 planes off: found to 0.05 px laterally and 0.25 um axially, with
 *    images of in-focus width and of deep-bead width;
 *  - another object's image, brighter, 2 px beside the bead's in 3 views:
 *    those views are not counted as agreeing and the position holds;
 *  - sparse noise alone (a time surface with no object) gives no fit at
 *    the guided search's 8 views;
 *  - too few views, an empty frame, NaN starts, bad options, a frame of the
 *    wrong size: no fit (0), no crash;
 *  - random frames and starts: every fit finite, inside the bounds it promises;
 *  - the fit over two frames of a moving bead (elfm_refocus_localize_frames);
 *  - two objects at one depth whose images overlap (a pair of C. elegans
 *    neurons 6 um apart, images 2.6 px wide): the plain fit pulls each
 *    towards the other, the fit that takes the other's light out
 *    (elfm_refocus_localize_near) does not; its bad inputs. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lfm_render.h"
#include "elfm_recon.h"

static double lcg(uint32_t *s)
{
  *s = *s * 1664525u + 1013904223u;
  return (*s >> 8) % 100001 / 100000.0;
}

/* voxel coordinates of (x, y, z) um in the plan's volume */
static void to_vox(const elfm_calib *c, const elfm_refocus_plan *p, double x, double y, double z,
                   double q[3])
{
  int w, h, nz;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  q[0] = x / c->um_per_px + 0.5 * (w - 1);
  q[1] = y / c->um_per_px + 0.5 * (h - 1);
  q[2] = (z - c->z_min_um) / c->z_step_um;
}

static void test_positions(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f,
                           double sigma_px)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  if (sigma_px > 2) o.half_window_px = 3;  /* a window for the wider image */
  const double fov_um = 0.5 * (c->view_w_px - 1) * c->um_per_px;
  uint32_t s = 11;
  double worst_lat = 0, worst_z = 0;
  int fitted = 0;
  for (int trial = 0; trial < 40; trial++) {
    double x = (2 * lcg(&s) - 1) * (fov_um - 30), y = (2 * lcg(&s) - 1) * (fov_um - 30);
    double z = (2 * lcg(&s) - 1) * 80.0;
    elfm_frame_clear(f);
    render_views(f, c, x, y, z, 255.0, sigma_px, 0, 0, 0);
    double q[3];
    to_vox(c, p, x, y, z, q);
    /* start off by up to 1 voxel laterally and 2 planes */
    const double s0 = q[0] + (2 * lcg(&s) - 1), s1 = q[1] + (2 * lcg(&s) - 1),
                 s2 = q[2] + 2 * (2 * lcg(&s) - 1);
    elfm_localize_result r;
    int ok = elfm_refocus_localize(p, f, s0, s1, s2, &o, &r);
    CHECK_MSG(ok, "bead (%.1f, %.1f, %.1f) um, sigma %.1f px: no fit", x, y, z, sigma_px);
    if (!ok) continue;
    fitted++;
    double lat = fmax(fabs(r.x_vox - q[0]), fabs(r.y_vox - q[1]));
    double ez = fabs(r.z_vox - q[2]) * c->z_step_um;
    if (lat > worst_lat) worst_lat = lat;
    if (ez > worst_z) worst_z = ez;
    CHECK_MSG(lat <= 0.05 && ez <= 0.25,
              "bead (%.2f, %.2f, %.2f) um, sigma %.1f px: off by %.3f px, %.3f um in z (%d views)",
              x, y, z, sigma_px, lat, ez, r.n_views);
    CHECK_MSG(r.n_views >= 20, "only %d views used", r.n_views);
  }
  printf("sigma %.1f px: %d of 40 fitted, worst %.3f px laterally, %.3f um axially\n", sigma_px,
         fitted, worst_lat, worst_z);
}

static void test_outlier_views(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  double x = 12.3, y = -20.7, z = 31.4, q[3];
  to_vox(c, p, x, y, z, q);
  elfm_frame_clear(f);
  render_views(f, c, x, y, z, 255.0, 1.3, 0, 0, 0);
  /* another object's image 2 px beside the bead's in views 0-2, brighter */
  render_views(f, c, x, y, z, 400.0, 1.3, 3, 3, 2.0);
  elfm_localize_result r;
  CHECK(elfm_refocus_localize(p, f, q[0] + 0.6, q[1] - 0.4, q[2] + 1.5, &o, &r));
  CHECK_MSG(fabs(r.x_vox - q[0]) <= 0.05 && fabs(r.y_vox - q[1]) <= 0.05 &&
                fabs(r.z_vox - q[2]) * c->z_step_um <= 0.25,
            "with 3 corrupted views: (%.3f %.3f %.3f) vs (%.3f %.3f %.3f), %d views",
            r.x_vox, r.y_vox, r.z_vox, q[0], q[1], q[2], r.n_views);
  CHECK_MSG(r.n_views <= 22, "the corrupted views were kept (%d views)", r.n_views);
}

/* Noise at the density of the simulator's background on a 1 ms time
 * surface (~0.5 % of pixels), no object: the guided search (min_views 8)
 * must not fit noise. */
static void test_noise_only(const elfm_refocus_plan *p, elfm_frame *f)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  o.min_views = 8;
  uint32_t s = 5;
  elfm_frame_clear(f);
  const int n = f->w * f->h / 200;
  for (int i = 0; i < n; i++) {
    uint32_t pix = (uint32_t)(lcg(&s) * (f->w * f->h - 1));
    elfm_frame_set(f, pix, (float)(60 + 195 * lcg(&s)));
  }
  int w, h, nz, fits = 0;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  for (int t = 0; t < 300; t++) {
    elfm_localize_result r;
    fits += elfm_refocus_localize(p, f, 10 + lcg(&s) * (w - 20), 10 + lcg(&s) * (h - 20),
                                  5 + lcg(&s) * (nz - 10), &o, &r);
  }
  printf("noise only: %d of 300 starts fitted at 8 views\n", fits);
  CHECK_MSG(fits <= 3, "%d of 300 noise starts fitted", fits);
}

static void test_no_fit(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  elfm_localize_result r;
  double q[3];
  to_vox(c, p, 5, 5, 10, q);
  elfm_frame_clear(f);
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &o, &r)); /* empty frame */
  render_views(f, c, 5, 5, 10, 255.0, 1.3, 5, 0, 0);                     /* 5 views only */
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &o, &r));
  o.min_views = 5;
  CHECK(elfm_refocus_localize(p, f, q[0], q[1], q[2], &o, &r));    /* enough at 5 */
  elfm_localize_options_default(&o);
  render_views(f, c, 5, 5, 10, 255.0, 1.3, 0, 0, 0);
  CHECK(elfm_refocus_localize(p, f, q[0], q[1], q[2], &o, &r));
  CHECK(!elfm_refocus_localize(p, f, NAN, q[1], q[2], &o, &r));
  CHECK(!elfm_refocus_localize(p, f, q[0], INFINITY, q[2], &o, &r));
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], NAN, &o, &r));
  CHECK(!elfm_refocus_localize(p, f, 1e300, -1e300, 1e300, &o, &r));
  CHECK(!elfm_refocus_localize(p, NULL, q[0], q[1], q[2], &o, &r));
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], NULL, &r));
  elfm_localize_options bad = o;
  bad.half_window_px = 0;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  bad = o;
  bad.power = 0;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  bad = o;
  bad.min_views = 1;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  bad = o;
  bad.outlier_px = NAN;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  /* passes beyond 100 are refused: INT_MAX once overflowed the pass count
   * (undefined; where it wrapped no pass ran and the fit read its views'
   * sums unset; found by clang's static analyzer) */
  bad = o;
  bad.iterations = INT_MAX;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  bad.iterations = 101;
  CHECK(!elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  bad.iterations = 100;
  CHECK(elfm_refocus_localize(p, f, q[0], q[1], q[2], &bad, &r));
  elfm_error err;
  elfm_frame *small = elfm_frame_create(640, 360, &err);
  CHECK(small != NULL);
  CHECK(!elfm_refocus_localize(p, small, q[0], q[1], q[2], &o, &r));
  elfm_frame_free(small);
  /* starts at the edges of the volume: any answer, no crash (ASan) */
  int w, h, nz;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  const double xs[3] = {-3, 0, w + 2.0}, zs[3] = {-5, 0, nz + 4.0};
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      for (int k = 0; k < 3; k++) (void)elfm_refocus_localize(p, f, xs[a], xs[b] * h / w, zs[k], &o, &r);
}

/* Random frames (noise, beads, negative values as a signed surface would
 * have) and random starts in and around the volume: every answer lies in
 * the volume's z range and within the walk-off bound of its start, with
 * finite numbers; nothing crashes (ASan/UBSan in CI). */
static void test_random_inputs(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  int w, h, nz, fits = 0, bad = 0;
  elfm_refocus_plan_size(p, &w, &h, &nz);
  uint32_t s = 99;
  for (int frame = 0; frame < 6; frame++) {
    elfm_frame_clear(f);
    for (int b = 0; b < 6; b++)
      render_views(f, c, (2 * lcg(&s) - 1) * 60, (2 * lcg(&s) - 1) * 60, (2 * lcg(&s) - 1) * 95,
                   50 + 400 * lcg(&s), 0.8 + 2.5 * lcg(&s), 0, 0, 0);
    const int n = f->w * f->h / 100;
    for (int i = 0; i < n; i++) {
      uint32_t pix = (uint32_t)(lcg(&s) * (f->w * f->h - 1));
      float val = (float)(255 * lcg(&s));
      if (frame % 2 && lcg(&s) < 0.5) val = -val;
      elfm_frame_set(f, pix, val);
    }
    for (int t = 0; t < 400; t++) {
      const double x0 = -10 + lcg(&s) * (w + 20), y0 = -10 + lcg(&s) * (h + 20),
                   z0 = -10 + lcg(&s) * (nz + 20);
      elfm_localize_options oo = o;
      oo.half_window_px = 1 + (int)(lcg(&s) * 4);
      oo.power = 1 + (int)(lcg(&s) * 4);
      oo.min_views = 2 + (int)(lcg(&s) * 10);
      elfm_localize_result r;
      if (!elfm_refocus_localize(p, f, x0, y0, z0, &oo, &r)) continue;
      fits++;
      const double lim = 2 * oo.half_window_px + 1e-9;
      bad += !(isfinite(r.x_vox) && isfinite(r.y_vox) && isfinite(r.z_vox) && isfinite(r.rms_px)) ||
             fabs(r.x_vox - x0) > lim || fabs(r.y_vox - y0) > lim || r.z_vox < -1.0 - 1e-9 ||
             r.z_vox > nz + 1e-9 || r.n_views < oo.min_views;
    }
  }
  printf("random inputs: %d fits of 2400 starts, %d out of bounds\n", fits, bad);
  CHECK_EQ_INT(bad, 0);
  CHECK(fits > 0);
}

/* elfm_refocus_localize_frames: a bead seen in 10 views of the wanted frame
 * and in all 25 of the frame before, where it was (3, -2, 4) um away. At
 * min_views 20 the wanted frame alone gives no fit; the two frames with the
 * right offset find the bead where it is now; with no offset the fit is
 * drawn to where it was (or fails), not to where it is. */
static void test_frames(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f)
{
  elfm_error err;
  elfm_frame *g = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
  CHECK(g != NULL);
  if (!g) return;
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  o.min_views = 20;
  const double x = -8.2, y = 14.9, z = 22.5, d[3] = {3.0, -2.0, 4.0};
  double q[3], q1[3];
  to_vox(c, p, x, y, z, q);
  to_vox(c, p, x + d[0], y + d[1], z + d[2], q1);
  elfm_frame_clear(f);
  elfm_frame_clear(g);
  render_views(f, c, x, y, z, 255.0, 1.3, 10, 0, 0);
  render_views(g, c, x + d[0], y + d[1], z + d[2], 255.0, 1.3, 0, 0, 0);
  elfm_localize_result r;
  CHECK(!elfm_refocus_localize(p, f, q[0] + 0.5, q[1] - 0.5, q[2] + 1, &o, &r));
  const elfm_frame *fr[2] = {f, g};
  const double off[2][3] = {{0, 0, 0}, {q1[0] - q[0], q1[1] - q[1], d[2]}};
  int ok = elfm_refocus_localize_frames(p, fr, off, 2, q[0] + 0.5, q[1] - 0.5, q[2] + 1, &o, &r);
  CHECK_MSG(ok, "two frames with the offset: no fit");
  if (ok) {
    CHECK_MSG(fabs(r.x_vox - q[0]) <= 0.05 && fabs(r.y_vox - q[1]) <= 0.05 &&
                  fabs(r.z_vox - q[2]) * c->z_step_um <= 0.25,
              "two frames: (%.3f %.3f %.3f) vs (%.3f %.3f %.3f)", r.x_vox, r.y_vox, r.z_vox, q[0],
              q[1], q[2]);
    CHECK_EQ_INT(r.n_views_first, 10);
    CHECK(r.n_views >= 20);
  }
  const double zero[2][3] = {{0, 0, 0}, {0, 0, 0}};
  ok = elfm_refocus_localize_frames(p, fr, zero, 2, q[0] + 0.5, q[1] - 0.5, q[2] + 1, &o, &r);
  CHECK_MSG(!ok || hypot(r.x_vox - q[0], r.y_vox - q[1]) > 1.0,
            "without the offset the fit should not find the bead where it is now");
  /* one frame, no offsets: the single-frame fit exactly */
  elfm_localize_result a, b;
  o.min_views = 6;
  CHECK(elfm_refocus_localize(p, g, q1[0] + 0.3, q1[1], q1[2], &o, &a));
  const elfm_frame *one[1] = {g};
  CHECK(elfm_refocus_localize_frames(p, one, NULL, 1, q1[0] + 0.3, q1[1], q1[2], &o, &b));
  CHECK(a.x_vox == b.x_vox && a.y_vox == b.y_vox && a.z_vox == b.z_vox && a.n_views == b.n_views);
  CHECK_EQ_INT(b.n_views_first, b.n_views);
  /* bad input: no frames, too many, a NaN offset */
  CHECK(!elfm_refocus_localize_frames(p, fr, off, 0, q[0], q[1], q[2], &o, &r));
  CHECK(!elfm_refocus_localize_frames(p, fr, off, 65, q[0], q[1], q[2], &o, &r));
  const double bad[2][3] = {{0, 0, 0}, {NAN, 0, 0}};
  CHECK(!elfm_refocus_localize_frames(p, fr, bad, 2, q[0], q[1], q[2], &o, &r));
  elfm_frame_free(g);
}

/* Object b at (x, y, z) with images sigma_px wide; another, brighter, d_um
 * away laterally and dz_um deeper (mode 0: alone, 1: the other there, plain
 * fit, 2: the other there and its position given to the fit). Writes b's fit
 * (voxels) to r and its truth to q. */
static int pair_fit(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f, double d_um,
                    double dz_um, int power, int mode, double q[3], elfm_localize_result *r)
{
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  o.power = power;
  o.half_window_px = 3; /* a window for the images' width, as test_positions */
  const double x = -8.2, y = 14.6, z = 35.0, sig = 2.6;
  double qo[3];
  to_vox(c, p, x, y, z, q);
  to_vox(c, p, x + d_um, y + 0.3 * d_um, z + dz_um, qo);
  elfm_frame_clear(f);
  render_views(f, c, x, y, z, 200.0, sig, 0, 0, 0);
  if (mode > 0) render_views(f, c, x + d_um, y + 0.3 * d_um, z + dz_um, 255.0, sig, 0, 0, 0);
  const double nb[1][3] = {{qo[0], qo[1], qo[2]}};
  const int ok = mode == 2 ? elfm_refocus_localize_near(p, f, q[0] + 0.4, q[1] - 0.3, q[2] + 0.5,
                                                        nb, 1, &o, r)
                           : elfm_refocus_localize(p, f, q[0] + 0.4, q[1] - 0.3, q[2] + 0.5, &o, r);
  CHECK_MSG(ok, "pair %.1f um apart, dz %.0f, power %d, mode %d: no fit", d_um, dz_um, power, mode);
  return ok;
}

/* lateral (px) and axial (um) distance between two fits */
static double fit_dist(const elfm_calib *c, const elfm_localize_result *a, const double b[3],
                       double *dz_um)
{
  *dz_um = fabs(a->z_vox - b[2]) * c->z_step_um;
  return hypot(a->x_vox - b[0], a->y_vox - b[1]);
}

static void test_near(const elfm_calib *c, const elfm_refocus_plan *p, elfm_frame *f)
{
  for (int power = 1; power <= 3; power += 2)
    for (int deeper = 0; deeper <= 1; deeper++) {
      /* deeper: the other object 20 um deeper, its images crossing the
       * bead's in a few outer views only */
      const double dz = deeper ? 20.0 : 0.0;
      double q[3], alone[3], ez0, ez1;
      elfm_localize_result r0, r1, r2;
      if (!pair_fit(c, p, f, 6.0, dz, power, 0, q, &r0) ||
          !pair_fit(c, p, f, 6.0, dz, power, 1, q, &r1) ||
          !pair_fit(c, p, f, 6.0, dz, power, 2, q, &r2))
        continue;
      alone[0] = r0.x_vox;
      alone[1] = r0.y_vox;
      alone[2] = r0.z_vox;
      const double e1 = fit_dist(c, &r1, alone, &ez0), e2 = fit_dist(c, &r2, alone, &ez1);
      printf("pair 6 um apart, dz %2.0f um, power %d: from the lone bead's fit, plain %.3f px / "
             "%.3f um in z, with the other taken out %.3f px / %.3f um\n", dz, power, e1, ez0, e2,
             ez1);
      if (!deeper) CHECK_MSG(e1 > 1.0, "the test needs overlapping images: plain only %.3f px", e1);
      /* at one depth the other's images sit beside the bead's in every
       * view and come out whole; 20 um deeper they cross the bead's in the
       * outer views, where within 2 px they are left in (and the robust
       * passes judge those views) */
      if (!deeper)
        CHECK_MSG(e2 < 0.05 && ez1 < 0.1, "other taken out: %.3f px, %.3f um", e2, ez1);
      else
        CHECK_MSG(e2 < 0.5 * e1 + 0.01 && ez1 < 0.5 * ez0 + 0.02,
                  "deeper other taken out: %.3f px, %.3f um (plain %.3f px, %.3f um)", e2, ez1, e1,
                  ez0);
    }
  /* no neighbours: the plain fit, exactly */
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  double q[3];
  to_vox(c, p, 3.0, -4.0, 10.0, q);
  elfm_frame_clear(f);
  render_views(f, c, 3.0, -4.0, 10.0, 255.0, 1.3, 0, 0, 0);
  elfm_localize_result a, b;
  CHECK(elfm_refocus_localize(p, f, q[0] + 0.5, q[1], q[2], &o, &a));
  CHECK(elfm_refocus_localize_near(p, f, q[0] + 0.5, q[1], q[2], NULL, 0, &o, &b));
  CHECK(a.x_vox == b.x_vox && a.y_vox == b.y_vox && a.z_vox == b.z_vox && a.n_views == b.n_views);
  /* bad neighbour lists: no fit, no crash */
  const double bad[1][3] = {{NAN, 0, 0}};
  CHECK(!elfm_refocus_localize_near(p, f, q[0], q[1], q[2], NULL, 1, &o, &b));
  CHECK(!elfm_refocus_localize_near(p, f, q[0], q[1], q[2], bad, 1, &o, &b));
  CHECK(!elfm_refocus_localize_near(p, f, q[0], q[1], q[2], bad, -1, &o, &b));
  /* a neighbour on top of the object (within 2 px in every view) is
   * ignored, not subtracted: the object's own light stays */
  const double same[1][3] = {{q[0] + 0.5, q[1], q[2]}};
  CHECK(elfm_refocus_localize_near(p, f, q[0] + 0.5, q[1], q[2], same, 1, &o, &b));
  CHECK(fabs(b.x_vox - a.x_vox) < 1e-9 && fabs(b.z_vox - a.z_vox) < 1e-9);
}

int main(void)
{
  elfm_calib c;
  elfm_optics op;
  elfm_error err;
  elfm_optics_default(&op);
  CHECK_OK(elfm_calib_from_optics(&op, 1280, 720, 4.86, &c, &err), &err);
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(&c, NULL, &p, &err), &err);
  elfm_frame *f = elfm_frame_create(c.sensor_width_px, c.sensor_height_px, &err);
  CHECK(p && f);
  if (!p || !f) return check_report();
  test_positions(&c, p, f, 1.3);
  test_positions(&c, p, f, 2.6);
  test_outlier_views(&c, p, f);
  test_noise_only(p, f);
  test_no_fit(&c, p, f);
  test_random_inputs(&c, p, f);
  test_frames(&c, p, f);
  test_near(&c, p, f);
  elfm_frame_free(f);
  elfm_refocus_plan_free(p);
  return check_report();
}
