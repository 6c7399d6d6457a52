/* test_calib_sweep.c — the views' centres from one object swept through z
 * (elfm_calib_sweep_*, recon/calib_sweep.c; `calib refine --sweep`):
 *  - frames drawn by hand: one bead swept from z -80 to +80 um, its image
 *    a Gaussian spot in every view but the central one (which shows only
 *    a faint spot 0.7 px off its image in some frames, as the central view
 *    of an axial sweep fires on the image's defocus alone), a hot pixel
 *    brighter than the bead in two views, a view whose image is lost under
 *    a brighter spot at random places, and noise everywhere; the start's
 *    centres up to ~9 px off. Every view ends within 0.08 px of the truth
 *    (the central one and the lost one set on the grid of the others and
 *    said to be), every frame tells the depth, and the views' moves, those
 *    placed too, carry neither of the moves no recording can see (their
 *    mean and their part in proportion to the disparities ~0, where the
 *    bead's place off the axis is 5 px);
 *  - the same frames with a second bead as bright, elsewhere: no view's
 *    spot stands out, nothing moves, and the calibration is untouched;
 *    one bead moved sideways instead of through z: nothing moves;
 *  - too few frames: nothing moves; bad arguments refused; a frame of
 *    another size gives no spots; a full collector takes no more;
 *  - `eventlfm calib refine --sweep` on a simulated z sweep (zsweep seed 1)
 *    from centres up to ~9 px off (where the command without --sweep took
 *    noise for a turn and fitted nothing, docs/recon.md): within 0.6 px
 *    (~0.5 measured: the inner views' lead of a one-way sweep), with the
 *    passes and without them (--passes 0, the fit alone); on a flow,
 *    where each view holds twenty beads moving each its own way, it
 *    refuses, writing nothing (several beads swept together:
 *    test_calib_sweep_beads.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "calib_test_util.h"
#include "check.h"
#include "cli_test_util.h"
#include "elfm_recon.h"

#define N_FRAMES 200
#define LOST 8

enum { ONE, TWIN, SIDEWAYS };

/* Frame k of the sweep: the bead at (5, -3) um, z from -80 to +80 um;
 * TWIN: a second bead as bright at (-30, 25) um, z the other way;
 * SIDEWAYS: the bead not swept but moved along x, -10 to +10 um, at z 10 */
static void draw(elfm_frame *f, const elfm_calib *truth, int k, int mode, uint32_t *seed)
{
  elfm_frame_clear(f);
  const double z = -80 + 160.0 * k / (N_FRAMES - 1);
  const int c0 = centre_view(truth);
  for (int v = 0; v < truth->n_views; v++) {
    double u, w;
    if (mode == SIDEWAYS)
      elfm_calib_project(truth, v, -10 + 20.0 * k / (N_FRAMES - 1), -3, 10, &u, &w);
    else
      elfm_calib_project(truth, v, 5, -3, z, &u, &w);
    if (v == LOST) /* a spot brighter than the image, anywhere in the view */
      frame_spot(f, truth->views[v].cx_px + 100 * (lcg(seed) - 0.5), truth->views[v].cy_px + 100 * (lcg(seed) - 0.5), 150);
    if (v != c0) frame_spot(f, u, w, 50);
    else if (k % 5 == 0) frame_spot(f, u + 0.7, w, 8); /* the central view: faint, and not where the image is */
    if (mode == TWIN) {
      elfm_calib_project(truth, v, -30, 25, -z, &u, &w);
      frame_spot(f, u, w, 50);
    }
  }
  /* hot pixels, brighter than any bead, in views 3 and 17 (25 px from
   * their centres), and noise: 400 pixels of 1-4 across the sensor */
  const int hot[2] = {3, 17};
  for (int h = 0; h < 2; h++)
    frame_put(f, lround(truth->views[hot[h]].cx_px) + 25, lround(truth->views[hot[h]].cy_px) - 20, 400);
  for (int n = 0; n < 400; n++)
    frame_put(f, (long)(lcg(seed) * (f->w - 1)), (long)(lcg(seed) * (f->h - 1)), (float)(1 + 3 * lcg(seed)));
}

/* Collect the N_FRAMES frames' spots and apply; views moved */
static int sweep_frames(const elfm_calib *truth, elfm_calib *c, elfm_frame *f, int mode, int n_frames,
                        elfm_calib_sweep **out)
{
  elfm_error err;
  elfm_calib_sweep *s = NULL;
  CHECK_OK(elfm_calib_sweep_create(c, N_FRAMES, &s, &err), &err);
  if (!s) return -1;
  uint32_t seed = 5;
  static elfm_calib_sweep_image img;
  for (int k = 0; k < n_frames; k++) {
    draw(f, truth, k * (N_FRAMES / n_frames), mode, &seed);
    CHECK_OK(elfm_calib_sweep_spots(s, f, &img, &err), &err);
    CHECK(elfm_calib_sweep_add(s, 1000 * (int64_t)k, &img));
  }
  CHECK(elfm_calib_sweep_frames(s) == (size_t)n_frames);
  int moved = -1;
  double shift[2 * ELFM_MAX_VIEWS];
  CHECK_OK(elfm_calib_sweep_apply(s, 20, c, shift, &moved, &err), &err);
  CHECK(elfm_calib_sweep_frames(s) == 0); /* emptied */
  *out = s;
  return moved;
}

static void test_by_hand(const elfm_calib *truth)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(truth->sensor_width_px, truth->sensor_height_px, &err);
  CHECK(f != NULL);
  if (!f) return;
  const int c0 = centre_view(truth);
  elfm_calib_sweep *s = NULL;

  /* one bead, centres up to ~9 px off */
  elfm_calib c = *truth;
  perturb(&c, 5, 21);
  const double before = centre_error(&c, truth);
  const elfm_calib start = c;
  int moved = sweep_frames(truth, &c, f, ONE, N_FRAMES, &s);
  double per[ELFM_MAX_VIEWS];
  const double after = centre_errors(&c, truth, per);
  elfm_calib_sweep_fit fit;
  elfm_calib_sweep_result(s, &fit);
  const int used = fit.frames_used, *images = fit.images, *placed = fit.placed;
  const double rms = fit.rms_px;
  printf("one bead swept through z by hand: centres up to %.2f px off -> %.4f px (the central view %.4f); "
         "%d frames told the depth, the images %.3f px RMS from the fit, %.5f um/ms\n", before, after, per[c0],
         used, rms, fit.speed_um_per_ms);
  /* 160 um in 199 frames 1 ms apart */
  CHECK_MSG(fabs(fit.speed_um_per_ms / (160.0 / 199) - 1) < 0.002 &&
            fit.speed_lo_um_per_ms <= fit.speed_um_per_ms && fit.speed_hi_um_per_ms >= fit.speed_um_per_ms,
            "the bead's speed %.5f um/ms (%.5f-%.5f)", fit.speed_um_per_ms, fit.speed_lo_um_per_ms,
            fit.speed_hi_um_per_ms);
  CHECK_MSG(before > 5 && after < 0.08, "centres up to %.3f px off after the sweep", after);
  CHECK_EQ_INT(moved, truth->n_views - 2);
  CHECK_EQ_INT(used, N_FRAMES);
  CHECK_MSG(rms < 0.1, "the images %.3f px RMS from the fit", rms);
  int n_placed = 0;
  for (int v = 0; v < truth->n_views; v++) {
    n_placed += placed[v];
    if (v != c0 && v != LOST) CHECK_MSG(images[v] > N_FRAMES * 9 / 10, "view %d: %d images", v, images[v]);
  }
  CHECK_EQ_INT(n_placed, 2);
  CHECK(placed[c0] && placed[LOST]);
  CHECK_MSG(images[LOST] < 20, "the lost view: %d images near the fit", images[LOST]);
  /* the moves of all the views (those placed too): no common part, none
   * in proportion to the disparities (least squares of move on (1, d), per
   * axis; cleared among the fitted views alone, the central view's start
   * 3.8 px off moved all by 0.1-0.5 px) */
  for (int axis = 0; axis < 2; axis++) {
    double n = 0, sd = 0, sdd = 0, sm = 0, sdm = 0;
    for (int v = 0; v < truth->n_views; v++) {
      const double d = axis ? truth->views[v].dy_px_per_um : truth->views[v].dx_px_per_um;
      const double m = axis ? c.views[v].cy_px - start.views[v].cy_px : c.views[v].cx_px - start.views[v].cx_px;
      n += 1;
      sd += d;
      sdd += d * d;
      sm += m;
      sdm += d * m;
    }
    const double b = (n * sdm - sd * sm) / (n * sdd - sd * sd), a = (sm - b * sd) / n;
    CHECK_MSG(fabs(a) < 0.01 && fabs(b) < 0.001, "axis %d: the moves' gauge part %.4f px + %.5f d", axis, a, b);
  }
  CHECK_MSG(per[3] < 0.08 && per[17] < 0.08, "views with a hot pixel %.3f / %.3f px off", per[3], per[17]);
  CHECK_EQ_INT(fit.objects, 1); /* its brightest spots fitted: no pattern of two */
  elfm_calib_sweep_free(s);

  /* two beads as bright, swept opposite ways: no spot stands out, and
   * the two are no pattern that moves as one; nothing moves */
  c = start;
  moved = sweep_frames(truth, &c, f, TWIN, N_FRAMES, &s);
  CHECK_EQ_INT(moved, 0);
  CHECK(memcmp(&c, &start, sizeof c) == 0);
  elfm_calib_sweep_result(s, &fit);
  printf("two beads swept opposite ways: a median %.2f of the spots near one fit, %.2f of the frames matched "
         "as several\n", fit.agree, fit.pattern_share);
  CHECK_EQ_INT(fit.objects, 1);
  CHECK_MSG(fit.pattern_share < 0.5, "two beads swept opposite ways: %.2f of the frames matched",
            fit.pattern_share);
  /* no brightest spot stands out twice over the other bead's: no frame
   * tells the depth (each would, by whichever bead is brighter there, were
   * every brightest spot kept) */
  CHECK_MSG(fit.frames_used < 20, "two beads as bright: %d frames told the depth", fit.frames_used);
  elfm_calib_sweep_free(s);

  /* one bead moved sideways, not through z (the wrong recording): its
   * images fit no depths (a median 0.23 of them near the fit, where 23
   * views had 20 images near it and would have moved); nothing moves */
  c = start;
  moved = sweep_frames(truth, &c, f, SIDEWAYS, N_FRAMES, &s);
  elfm_calib_sweep_result(s, &fit);
  printf("one bead moved sideways: a median %.2f of the spots near the fit, two spots in %.2f of the frames\n",
         fit.agree, fit.several_share);
  CHECK_EQ_INT(moved, 0);
  CHECK(memcmp(&c, &start, sizeof c) == 0);
  CHECK(fit.agree < 0.5 && fit.several_share < 0.5);
  elfm_calib_sweep_free(s);

  /* 10 frames: fewer than the 20 images a view needs */
  moved = sweep_frames(truth, &c, f, ONE, 10, &s);
  CHECK_EQ_INT(moved, 0);
  CHECK(memcmp(&c, &start, sizeof c) == 0);

  /* a frame of another size: no spots; a full collector takes no more */
  elfm_frame *small = elfm_frame_create(64, 48, &err);
  CHECK(small != NULL);
  static elfm_calib_sweep_image img;
  if (small) {
    frame_put(small, 10, 10, 100);
    CHECK_OK(elfm_calib_sweep_spots(s, small, &img, &err), &err);
    for (int v = 0; v < truth->n_views; v++)
      CHECK(isnan(img.at_px[2 * v]) && img.contrast[v] == 0 && img.n_spots[v] == 0);
    elfm_frame_free(small);
  }
  for (int k = 0; k < N_FRAMES; k++) CHECK(elfm_calib_sweep_add(s, k, &img));
  CHECK(!elfm_calib_sweep_add(s, 0, &img));
  /* apply on a calibration of other views */
  elfm_calib other = *truth;
  other.n_views = 9;
  elfm_error_clear(&err);
  CHECK(elfm_calib_sweep_apply(s, 20, &other, NULL, NULL, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "views") != NULL);
  elfm_calib_sweep_free(s);
  elfm_calib_sweep_free(NULL);

  /* bad arguments */
  elfm_calib_sweep *bad = NULL;
  CHECK(elfm_calib_sweep_create(truth, 0, &bad, &err) == ELFM_ERR_INVALID && bad == NULL);
  other = *truth;
  other.n_views = 0;
  CHECK(elfm_calib_sweep_create(&other, 10, &bad, &err) == ELFM_ERR_INVALID && bad == NULL);
  elfm_frame_free(f);
}

static char dir[] = "/tmp/elfm_calib_sweep_XXXXXX";

static void test_cli(void)
{
  char args[3000], p[800];
  if (!cli_test_ready(dir)) return;
  elfm_error err;
  elfm_calib truth, r;
  snprintf(args, sizeof args, "simulate zsweep --seed 1 --out %s/zs --no-truth --quiet", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(p, sizeof p, "%s/zs/calib.json", dir);
  CHECK_OK(elfm_calib_load(p, &truth, &err), &err);
  elfm_calib start = truth;
  perturb(&start, 5, 21);
  snprintf(p, sizeof p, "%s/start.json", dir);
  CHECK_OK(elfm_calib_save(&start, p, &err), &err);
  snprintf(args, sizeof args, "calib refine --sweep --calib %s --events %s/zs/events.raw --out %s/r.json "
           "--passes 2", p, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "calib refine: the sweep's views, frame by frame: "));
  CHECK(!cli_file_has(dir, "err.txt", "the lens array's turn:"));
  snprintf(p, sizeof p, "%s/r.json", dir);
  CHECK_OK(elfm_calib_load(p, &r, &err), &err);
  const double before = centre_error(&start, &truth), after = centre_error(&r, &truth);
  printf("zsweep seed 1, calib refine --sweep: centres up to %.2f px off -> %.3f px\n", before, after);
  CHECK_MSG(before > 5 && after < 0.6, "centres up to %.3f px off after --sweep", after);

  /* --passes 0: the sweep's fit alone (0.202-0.226 px RMS on seeds 1-4,
   * as good as with the passes) */
  snprintf(p, sizeof p, "%s/start.json", dir);
  snprintf(args, sizeof args, "calib refine --sweep --calib %s --events %s/zs/events.raw --out %s/r0.json "
           "--passes 0", p, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "frame by frame") && !cli_file_has(dir, "err.txt", "pass 1:"));
  snprintf(p, sizeof p, "%s/r0.json", dir);
  CHECK_OK(elfm_calib_load(p, &r, &err), &err);
  printf("... --passes 0: %.3f px\n", centre_error(&r, &truth));
  CHECK_MSG(centre_error(&r, &truth) < 0.6, "--passes 0: centres up to %.3f px off", centre_error(&r, &truth));

  /* the depth scale: zsweep with a relay 2.4 % longer than the optics'
   * calibration's (every disparity 2.4 % longer, the outer views' centres
   * 7-10 px out), refined from that calibration with the piezo's 0.2 um/ms:
   * the disparities come within 1 % of the truth's (0.7 % short measured:
   * the fitted depths fall short away from focus), where the optics' are
   * 2.4 % short; without the speed they stay the optics' and the speed
   * measured says 0.20 um/ms (--keep-scale: the relay's scale that the
   * views' grid shows once the focal plane has moved, which would come
   * first, is test_calib_sweep_focus.c's) */
  snprintf(args, sizeof args, "simulate zsweep --seed 1 --param optics.relay=1.28 --out %s/zr --no-truth --quiet",
           dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args, "calib from-optics --out %s/optics.json", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  elfm_calib relay;
  snprintf(p, sizeof p, "%s/zr/calib.json", dir);
  CHECK_OK(elfm_calib_load(p, &relay, &err), &err);
  snprintf(args, sizeof args, "calib refine --sweep-um-per-ms 0.2 --calib %s/optics.json --events %s/zr/events.raw "
           "--out %s/zr.json --passes 1 --keep-scale", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "the disparities scaled by 1.01"));
  snprintf(p, sizeof p, "%s/zr.json", dir);
  CHECK_OK(elfm_calib_load(p, &r, &err), &err);
  const int corner = 0;
  const double ratio = r.views[corner].dx_px_per_um / relay.views[corner].dx_px_per_um;
  printf("... a relay 2.4 %% longer, the piezo's speed given: disparities x %.4f of the truth's, centres "
         "%.3f px off\n", ratio, centre_error(&r, &relay));
  CHECK_MSG(fabs(ratio - 1) < 0.01, "disparities %.4f of the truth's", ratio);
  CHECK_MSG(centre_error(&r, &relay) < 0.6, "centres %.3f px off", centre_error(&r, &relay));
  snprintf(args, sizeof args, "calib refine --sweep --calib %s/optics.json --events %s/zr/events.raw "
           "--out %s/zr0.json --passes 0 --keep-scale", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  CHECK(cli_file_has(dir, "err.txt", "the object moved in z at 0.20") &&
        cli_file_has(dir, "err.txt", "--sweep-um-per-ms with the piezo's speed"));
  snprintf(args, sizeof args, "calib refine --sweep-um-per-ms 0.02 --calib %s/optics.json --events "
           "%s/zr/events.raw --out %s/zr2.json --passes 0", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 1);
  CHECK(cli_file_has(dir, "err.txt", "the speed's units are um per ms"));
  snprintf(p, sizeof p, "%s/zr2.json", dir);
  CHECK_MSG(access(p, F_OK) != 0, "a refused scale wrote %s", p);

  /* a flow: twenty beads in every view */
  snprintf(args, sizeof args, "simulate flow --seed 1 --duration-ms 30 --out %s/fl --no-truth --quiet", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args, "calib refine --sweep --calib %s/fl/calib.json --events %s/fl/events.raw "
           "--out %s/f.json", dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 1);
  CHECK(cli_file_has(dir, "err.txt", "one object, or several side by side, swept together through z") &&
        cli_file_has(dir, "err.txt", "several objects in the views (a median 1.00 of the frames hold two") &&
        cli_file_has(dir, "err.txt", "of the frames matched it, 0.5 or more needed"));
  /* as several objects: the beads of one frame match another frame's by
   * chance in a few views (0.08 measured) */
  char text[4096];
  const char *at = NULL;
  double share = 1;
  if (cli_read_file(dir, "err.txt", text, sizeof text) &&
      (at = strstr(text, "do not move as one pattern: ")) != NULL)
    share = atof(at + strlen("do not move as one pattern: "));
  CHECK_MSG(at && share < 0.2, "a flow's frames matched a pattern in %.2f", share);
  snprintf(p, sizeof p, "%s/f.json", dir);
  CHECK_MSG(access(p, F_OK) != 0, "a refused sweep wrote %s", p);

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
