/* test_calib_sweep_beads.c — several beads swept through z together
 * (calib_sweep_pattern.c, `calib refine --sweep` on a slide of beads):
 *  - frames drawn by hand: six beads scattered over 40 x 30 um, each as
 *    bright as the others give or take 30 % at random from view to view and
 *    frame to frame (so the brightest spot is now one bead's, now
 *    another's, and no one object fits), swept from z -60 to +60 um, hot
 *    pixels and noise, the central view faint; the start's centres up to
 *    ~9 px off. On one depth, and at depths 11 um apart (the beads' images
 *    then lie apart otherwise in every view, by up to 8 px per axis between
 *    opposite corner views): the six found, their depths' spread measured
 *    to 0.3 um, every view within 0.08 px of the truth;
 *  - six beads each moving through z its own way (a flow, not a sweep):
 *    refused, nothing moves; two beads swept opposite ways, each the
 *    brighter in some views (one object's fit would take each view's
 *    brighter bead, right in some, off by the beads' distance in the
 *    others): refused; one
 *    bead, and in one view a brighter spot beside its image moving with
 *    it: that view fits the spot, off the lenslets' grid: refused;
 *    25 beads on a grid 16 um apart (more spots in a view than the 8 a
 *    view's list held before): all in the pattern, every view within
 *    0.08 px;
 *  - `eventlfm calib refine --sweep` on five simulated beads 10 um apart on
 *    a slide tilted by 20 degrees (zsweep, objects.count=5): fitted as one
 *    pattern within 0.45 px, the beads' 14.6 um of depth said; thirty
 *    scattered over a disc 100 um across (motion.place_radius_um=50):
 *    fitted within 0.3 px, 16 or more of them in the pattern. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "calib_test_util.h"
#include "check.h"
#include "cli_test_util.h"
#include "elfm_recon.h"

#define N_BEADS 6
#define N_FRAMES 200
/* the beads' lateral places, um (none nearer another than 10 um) */
static const double bead_um[N_BEADS][2] = {{0, 0}, {14, 3}, {-12, 9}, {6, -15}, {-18, -11}, {22, 16}};
/* their depths against the first's, um, on an uneven slide */
static const double bead_dz_um[N_BEADS] = {0, 4, -3, 6, -5, 2};

enum { TOGETHER, APART, TWO_OPPOSITE, DECOY, MANY };
#define DECOY_VIEW 6
/* MANY: 25 beads on a 5 x 5 grid 16 um apart, each moved up to 3 um (none
 * nearer another than 10 um): 25 spots in a view, where a list of 8 spots
 * held a different eight beads from view to view and frame to frame */
#define N_MANY 25

static void bead_at(int mode, int b, double *x_um, double *y_um)
{
  if (mode != MANY) {
    *x_um = bead_um[b][0];
    *y_um = bead_um[b][1];
    return;
  }
  *x_um = 16.0 * (b % 5 - 2) + 1.5 * ((b * 7) % 5 - 2);
  *y_um = 16.0 * (b / 5 - 2) + 1.5 * ((b * 3) % 5 - 2);
}

/* Frame k: the beads at z from -60 to +60 um, each at depth z + dz[b]
 * (scaled by `uneven`); APART: each at its own speed and start;
 * TWO_OPPOSITE: the first two beads alone, swept opposite ways, the first
 * 2.5 x the second in views 0-17, the second 2.5 x the first in the rest;
 * DECOY: the first bead alone, and in view DECOY_VIEW a spot 3 x as bright
 * 7 px beside its image, moving with it */
static void draw(elfm_frame *f, const elfm_calib *truth, int k, double uneven, int mode, uint32_t *seed)
{
  elfm_frame_clear(f);
  const int c0 = centre_view(truth);
  const int nb = mode == TWO_OPPOSITE ? 2 : mode == DECOY ? 1 : mode == MANY ? N_MANY : N_BEADS;
  for (int b = 0; b < nb; b++) {
    double x_um, y_um;
    bead_at(mode, b, &x_um, &y_um);
    const double z0 = -60 + 120.0 * k / (N_FRAMES - 1) + (mode == MANY ? 0 : uneven * bead_dz_um[b]);
    const double z = mode == APART          ? -50 + 100.0 * fmod(0.37 * b + (0.5 + 0.3 * b) * k / N_FRAMES, 1.0)
                     : mode == TWO_OPPOSITE && b == 1 ? -z0
                                                      : z0;
    for (int v = 0; v < truth->n_views; v++) {
      double u, w;
      elfm_calib_project(truth, v, x_um, y_um, z, &u, &w);
      double peak = 50 * (0.7 + 0.6 * lcg(seed));
      if (mode == TWO_OPPOSITE) peak = (b == (v >= 18)) ? 50 : 20;
      if (mode == DECOY && v == DECOY_VIEW) frame_spot(f, u + 7, w, 3 * peak);
      if (v != c0) frame_spot(f, u, w, peak);
      else if (k % 5 == 0) frame_spot(f, u + 0.7, w, 8);
    }
  }
  for (int h = 0; h < 2; h++)
    frame_put(f, lround(truth->views[3 + 14 * h].cx_px) + 25, lround(truth->views[3 + 14 * h].cy_px) - 20, 400);
  for (int n = 0; n < 400; n++)
    frame_put(f, (long)(lcg(seed) * (f->w - 1)), (long)(lcg(seed) * (f->h - 1)), (float)(1 + 3 * lcg(seed)));
}

/* The frames' spots collected and applied to c; the fit into *fit; the
 * views moved */
static int sweep(const elfm_calib *truth, elfm_calib *c, elfm_frame *f, double uneven, int mode,
                 elfm_calib_sweep_fit *fit)
{
  elfm_error err;
  elfm_calib_sweep *s = NULL;
  CHECK_OK(elfm_calib_sweep_create(c, N_FRAMES, &s, &err), &err);
  if (!s) return -1;
  uint32_t seed = 9;
  static elfm_calib_sweep_image img;
  for (int k = 0; k < N_FRAMES; k++) {
    draw(f, truth, k, uneven, mode, &seed);
    CHECK_OK(elfm_calib_sweep_spots(s, f, &img, &err), &err);
    CHECK(elfm_calib_sweep_add(s, 1000 * (int64_t)k, &img));
  }
  int moved = -1;
  CHECK_OK(elfm_calib_sweep_apply(s, 20, c, NULL, &moved, &err), &err);
  elfm_calib_sweep_result(s, fit);
  elfm_calib_sweep_free(s);
  return moved;
}

static void test_by_hand(const elfm_calib *truth)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(truth->sensor_width_px, truth->sensor_height_px, &err);
  CHECK(f != NULL);
  if (!f) return;
  elfm_calib start = *truth;
  perturb(&start, 5, 21);
  const double before = centre_error(&start, truth);
  elfm_calib_sweep_fit fit;
  for (int uneven = 0; uneven < 2; uneven++) {
    elfm_calib c = start;
    const int moved = sweep(truth, &c, f, uneven, TOGETHER, &fit);
    const double after = centre_error(&c, truth);
    printf("six beads swept together%s: centres up to %.2f px off -> %.4f px; %d objects, %.2f um apart in "
           "depth, the pattern matched in %.2f of the frames\n", uneven ? " at depths 11 um apart" : "", before,
           after, fit.objects, fit.depth_um, fit.pattern_share);
    CHECK_EQ_INT(fit.objects, N_BEADS);
    CHECK_MSG(fabs(fit.depth_um - 11 * uneven) < 0.3, "the beads %.2f um apart in depth", fit.depth_um);
    CHECK_MSG(fit.pattern_share > 0.8, "the pattern matched in %.2f of the frames", fit.pattern_share);
    CHECK_MSG(before > 5 && after < 0.08, "centres up to %.3f px off after the sweep", after);
    CHECK_EQ_INT(moved, truth->n_views - 1);
    CHECK_MSG(fit.off_grid_px >= 0 && fit.off_grid_px < 0.2, "the views %.3f px off their grid", fit.off_grid_px);
  }
  /* 25 beads: more than a view's spots listed before (8), each view's
   * list the brightest of 25 as bright as each other: the pattern holds
   * them all */
  elfm_calib c = start;
  int moved = sweep(truth, &c, f, 0, MANY, &fit);
  printf("25 beads on a slide: centres up to %.2f px off -> %.4f px; %d objects, the pattern matched in %.2f of "
         "the frames\n", before, centre_error(&c, truth), fit.objects, fit.pattern_share);
  CHECK_MSG(fit.objects >= 20, "%d objects of 25", fit.objects);
  CHECK_MSG(fit.pattern_share > 0.8, "the pattern matched in %.2f of the frames", fit.pattern_share);
  CHECK_MSG(centre_error(&c, truth) < 0.08, "centres %.3f px off", centre_error(&c, truth));
  CHECK_EQ_INT(moved, truth->n_views - 1);
  /* each its own way: no pattern (0.00 of the frames matched it; 0.36
   * where two spots of six that agree were a match) */
  c = start;
  moved = sweep(truth, &c, f, 0, APART, &fit);
  printf("six beads each moving its own way: %.2f of the frames matched a pattern\n", fit.pattern_share);
  CHECK_EQ_INT(moved, 0);
  CHECK_EQ_INT(fit.objects, 1);
  CHECK_MSG(fit.pattern_share < 0.2, "%.2f of the frames matched", fit.pattern_share);
  CHECK(memcmp(&c, &start, sizeof c) == 0);
  /* two beads swept opposite ways, each the brighter in some views: no
   * pattern, and each view's brightest spot stands out (2.5 x the other
   * bead's), so one object fits every view, 7 of them on the other bead.
   * Two spots in every frame: refused */
  c = start;
  moved = sweep(truth, &c, f, 0, TWO_OPPOSITE, &fit);
  printf("two beads swept opposite ways, each the brighter in some views: two spots or more in %.2f of the "
         "frames, a median %.2f of the brightest near one object's fit\n", fit.several_share, fit.agree);
  CHECK_MSG(fit.agree >= 0.5, "the brightest spots %.2f near one fit", fit.agree);
  CHECK(fit.several_share >= ELFM_CALIB_SWEEP_SEVERAL && fit.objects == 1);
  CHECK_EQ_INT(moved, 0);
  CHECK(memcmp(&c, &start, sizeof c) == 0);
  /* one view fitted to another object's images (as a row of beads taken
   * for their neighbours: the images fit, the view does not lie on the
   * lenslets' grid): refused, naming the view */
  c = start;
  moved = sweep(truth, &c, f, 0, DECOY, &fit);
  printf("one bead, and in view %d a brighter spot beside it: that view %.2f px off the grid (%d frames told "
         "the depth, a median %.2f of the spots near the fit)\n", DECOY_VIEW, fit.off_grid_px, fit.frames_used,
         fit.agree);
  CHECK_MSG(fit.agree >= 0.5 && fit.objects == 1 && fit.frames_used == N_FRAMES, "the brightest spots %.2f near "
            "one fit, %d frames", fit.agree, fit.frames_used);
  CHECK_EQ_INT(fit.off_grid_view, DECOY_VIEW);
  CHECK_MSG(fit.off_grid_px > 5, "the view %.2f px off the grid", fit.off_grid_px);
  CHECK_EQ_INT(moved, 0);
  CHECK(memcmp(&c, &start, sizeof c) == 0);
  elfm_frame_free(f);
}

static char dir[] = "/tmp/elfm_calib_beads_XXXXXX";

static void test_cli(void)
{
  char args[3000], p[800];
  if (!cli_test_ready(dir)) return;
  elfm_error err;
  elfm_calib truth, r;
  snprintf(args, sizeof args, "simulate zsweep --seed 1 --param objects.count=5 --param motion.tilt_deg=20 "
           "--out %s/z5 --no-truth --quiet", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(p, sizeof p, "%s/z5/calib.json", dir);
  CHECK_OK(elfm_calib_load(p, &truth, &err), &err);
  elfm_calib start = truth;
  perturb(&start, 5, 21);
  snprintf(p, sizeof p, "%s/start.json", dir);
  CHECK_OK(elfm_calib_save(&start, p, &err), &err);
  snprintf(args, sizeof args, "calib refine --sweep --calib %s --events %s/z5/events.raw --out %s/r.json --passes 0",
           p, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "(5 objects side by side, 14."));
  CHECK(cli_file_has(dir, "err.txt", " um apart in depth at most, their pattern matched in a median 0."));
  snprintf(p, sizeof p, "%s/r.json", dir);
  CHECK_OK(elfm_calib_load(p, &r, &err), &err);
  printf("zsweep, five beads on a slide tilted 20 degrees: centres up to %.2f px off -> %.3f px\n",
         centre_error(&start, &truth), centre_error(&r, &truth));
  CHECK_MSG(centre_error(&r, &truth) < 0.45, "centres %.3f px off", centre_error(&r, &truth));
  /* thirty beads scattered over a disc 100 um across (a slide as it is
   * dried), swept twice as fast over half the depth range (the
   * simulator's time: 6 s), so that 25-30 images fill each view: listed
   * 8 to a view, each view's eight were other beads than the next's, and
   * the sweep was refused (their pattern matched in 0.43 of the frames).
   * Fitted as one pattern, the beads named */
  snprintf(args, sizeof args, "simulate zsweep --seed 1 --param objects.count=30 --param "
           "motion.place_radius_um=50 --param duration_ms=450 --param motion.speed_mm_per_s=0.4 --out %s/z30 "
           "--no-truth --quiet", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args, "calib refine --sweep --calib %s/start.json --events %s/z30/events.raw --out "
           "%s/r30.json --passes 0", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  int objects = 0;
  static char text[1 << 16];
  const char *at = cli_read_file(dir, "err.txt", text, sizeof text) ? strstr(text, "frame by frame (") : NULL;
  CHECK_MSG(at && sscanf(at, "frame by frame (%d objects side by side", &objects) == 1 && objects >= 16,
            "%d objects named", objects);
  snprintf(p, sizeof p, "%s/r30.json", dir);
  CHECK_OK(elfm_calib_load(p, &r, &err), &err);
  printf("zsweep, thirty beads scattered on a slide: centres up to %.2f px off -> %.3f px, %d objects\n",
         centre_error(&start, &truth), centre_error(&r, &truth), objects);
  CHECK_MSG(centre_error(&r, &truth) < 0.3, "centres %.3f px off", centre_error(&r, &truth));
  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

int main(void)
{
  elfm_calib c;
  if (!calib_test_default(&c)) return check_report();
  test_by_hand(&c);
  test_cli();
  return check_report();
}
