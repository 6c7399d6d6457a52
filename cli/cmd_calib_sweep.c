/* cmd_calib_sweep.c — `calib refine --sweep`'s step (the rest of the
 * command: cmd_calib_refine.c): each view's images found frame by frame
 * and the centres fitted to them; the sweep read backwards as well; then
 * the focal plane where the object was in focus, the relay's magnification
 * from the views' grid, and the depth scale from the piezo's speed. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cmd_calib_refine.h"

static const char *const C = "calib refine";

/* The depth scale: the fitted depths move at the speed the disparities
 * give them; a piezo's known speed scales the disparities (every view's by
 * one factor: the centres fitted stay right, image = centre + d z being
 * unchanged with d x k and z / k). A relay magnification 2.4 % off, which
 * no recording of unknown motion shows (docs/recon.md), is such a factor. */
static int sweep_scale(elfm_calib *cal, const elfm_calib_sweep_fit *fit, double relay_k, const char *events,
                       double speed, int quiet)
{
  /* the fit's depths were by the disparities before the relay's scale,
   * which shortens them by its factor */
  const double v = fit->speed_um_per_ms / relay_k;
  if (!quiet && isfinite(v))
    fprintf(stderr, "calib refine: the object moved in z at %.4f um/ms by the disparities as they are (the "
            "middle half of 40 ms spans in the middle half of its depths %.4f-%.4f)%s\n", v,
            fit->speed_lo_um_per_ms / relay_k, fit->speed_hi_um_per_ms / relay_k,
            speed > 0 ? "" : "; --sweep-um-per-ms with the piezo's speed scales the depths to it");
  if (!(speed > 0)) return CLI_OK;
  if (!isfinite(v))
    return cli_message(C, CLI_FAIL, "%s: too few frames told the depth to measure the object's speed by "
                       "(--sweep-um-per-ms)", events);
  const double k = v / speed;
  if (!(k > 0.5 && k < 2))
    return cli_message(C, CLI_FAIL, "%s: the object moved at %.4f um/ms, --sweep-um-per-ms %g: the "
                       "disparities would be scaled by %.3f (0.5..2 expected: the speed's units are um per ms)",
                       events, v, speed, k);
  for (int w = 0; w < cal->n_views; w++) {
    cal->views[w].dx_px_per_um *= k;
    cal->views[w].dy_px_per_um *= k;
  }
  if (!quiet)
    fprintf(stderr, "calib refine: the disparities scaled by %.4f to the piezo's %g um/ms\n", k, speed);
  return CLI_OK;
}

/* The focal plane: where the sweep's images were strongest (the object in
 * focus), which no fit of their places sees (a move of every view along
 * its disparity is an offset of z), made z = 0 unless --keep-focal-plane.
 * A calibration from the optics puts it where they say: a relay 2.4 %
 * longer than the optics' put it 21 um off. One way, the focus leans
 * towards the way the object went (14 simulated one-way sweeps on the 5 x
 * 5 array: -0.93..+1.91 um, 3.56 on a 3 x 3 array): fw and back (not NULL
 * for a one-way sweep read both ways) lean apart, by 1.1-6.7 um, and
 * their mean is taken (-1.49..+0.90); a sweep up and down gives each
 * way's focus in fit, and their mean (docs/recon.md "A one-way sweep read
 * both ways"). Nearer than FOCUS_TOL_UM a sweep does not tell it better
 * than the calibration has it. 1 when it moved the focal plane. */
#define FOCUS_TOL_UM 2.0
static int sweep_focus(elfm_calib *cal, const elfm_calib_sweep_fit *fit, const elfm_calib_sweep_fit *fw,
                       const elfm_calib_sweep_fit *back, int keep, int quiet)
{
  const int both = fw && back && isfinite(fw->focus_um) && isfinite(back->focus_um);
  const double z = both ? 0.5 * (fw->focus_um + back->focus_um) : fit->focus_um;
  if (!isfinite(z)) {
    if (!quiet)
      fprintf(stderr, "calib refine: the sweep's images were strongest at no depth it went through and out of "
              "both ways: the focal plane kept\n");
    return 0;
  }
  const int move = !keep && fabs(z) > FOCUS_TOL_UM;
  if (move) elfm_calib_move_focus(cal, z);
  char said[200] = "";
  if (both)
    snprintf(said, sizeof said, " (one way: the mean of the sweep read forwards, %+.2f, and backwards, %+.2f)",
             fw->focus_um, back->focus_um);
  else if (fw && back)
    snprintf(said, sizeof said, " (one way, the fit's own: read %s on the integral started empty, it showed none)",
             !isfinite(fw->focus_um) && !isfinite(back->focus_um) ? "either way"
             : !isfinite(fw->focus_um)                            ? "forwards"
                                                                  : "backwards");
  else if (isfinite(fit->focus_up_um) && isfinite(fit->focus_down_um))
    snprintf(said, sizeof said, " (the mean of the way up's %+.2f and the way down's %+.2f)", fit->focus_up_um,
             fit->focus_down_um);
  if (!quiet) {
    fprintf(stderr, "calib refine: the sweep's images were strongest at z %+.2f um of the fitted depths%s: ", z, said);
    if (move)
      fprintf(stderr, "the focal plane moved there\n");
    else if (keep)
      fprintf(stderr, "the focal plane kept (--keep-focal-plane)\n");
    else
      fprintf(stderr, "within %g um, as near as a sweep tells it, the focal plane kept\n", FOCUS_TOL_UM);
  }
  return move;
}

/* The relay's magnification. With the focal plane where the object was in
 * focus, the fitted centres are the views' own (the images of a point in
 * focus), and their grid's pitch against the start's is the relay's error:
 * the lenslets' pitch and the pixels' are known to well under 0.1 %, and
 * the relay scales everything on the sensor alike (elfm_calib_grid_pitch).
 * Before, a wider grid was all but the focal plane's offset and the fit
 * took it for that (docs/recon.md "What it still cannot see"), so the
 * pitch's change is the focal plane's move seen on the grid, 0.12 % per um
 * on the paper's system, and its error the focus's: a relay 2.4 % longer
 * than the optics', 2.18-2.64 % measured on 12 sweeps. moved: the focal
 * plane moved (else the grid is the start's). The factor taken (1: none). */
static double sweep_relay(elfm_calib *cal, const elfm_calib *start, int moved, int keep, int quiet)
{
  if (!moved) return 1;
  const double k = elfm_calib_grid_pitch(cal) / elfm_calib_grid_pitch(start);
  if (!isfinite(k)) return 1;
  const double um_per_px = cal->um_per_px;
  if (!keep) elfm_calib_scale_relay(cal, k);
  if (!quiet) {
    fprintf(stderr, "calib refine: the views' grid is %.4f x the start's: ", k);
    if (keep)
      fprintf(stderr, "the scale kept (--keep-scale)\n");
    else
      fprintf(stderr, "the relay's magnification, um_per_px %.4f -> %.4f and every disparity x %.4f\n", um_per_px,
              cal->um_per_px, k);
  }
  return keep ? 1 : k;
}

/* After the fit: the sweep's focus (fit's, or the mean of fw's and back's:
 * a one-way sweep read both ways) made z = 0 unless keep_focus; then,
 * the focal plane moved, the relay's magnification from the views' grid
 * against start's unless keep_scale; the disparities scaled to the
 * piezo's speed (um/ms, 0: not known). CLI_OK or CLI_FAIL (said). */
static int sweep_finish(elfm_calib *cal, const elfm_calib *start, const elfm_calib_sweep_fit *fit,
                        const elfm_calib_sweep_fit *fw, const elfm_calib_sweep_fit *back, const char *events,
                        double speed_um_per_ms, int keep_focus, int keep_scale, int quiet)
{
  const int moved = sweep_focus(cal, fit, fw, back, keep_focus, quiet);
  const double k = sweep_relay(cal, start, moved, keep_scale, quiet);
  return sweep_scale(cal, fit, k, events, speed_um_per_ms, quiet);
}

/* One pass of the sweep's step over c->events on recon's frames, from the
 * centres in *cal:
 * the fitted centres into *cal, their moves into shift[], the fit into
 * *fit, the frames read into *frames. */
static elfm_status sweep_pass(refine_ctx *c, const elfm_recon_options *recon, elfm_calib *cal, double *shift,
                              int *moved, elfm_calib_sweep_fit *fit, size_t *frames, elfm_error *err)
{
  const refine_opts *o = c->o;
  const double frame_ms = (double)recon->framer.dt_us / 1000.0;
  const size_t max_frames = (size_t)ceil(o->ms / frame_ms) + 2;
  elfm_status st = elfm_calib_sweep_create(cal, max_frames, &c->sweep, err);
  if (st != ELFM_OK) return st;
  /* the spots are read off the frames (the worker above): refocusing every
   * frame's volume, which nothing read, was most of a sweep's time (one
   * bead over 0.9 s: 2.6-3.2 s -> 0.44 s) */
  elfm_recon_options ro = *recon;
  ro.no_refocus = 1;
  st = refine_run_pass(c, cal, ro, err);
  *frames = elfm_calib_sweep_frames(c->sweep);
  if (st == ELFM_OK) st = elfm_calib_sweep_apply(c->sweep, o->min_points, cal, shift, moved, err);
  elfm_calib_sweep_result(c->sweep, fit);
  elfm_calib_sweep_free(c->sweep);
  c->sweep = NULL;
  return st;
}

/* A reading that fitted no views because most frames held two spots or
 * more in a view that did not move as one pattern: the mark of sensor
 * noise beside a faint image, which the 3 x 3 median takes out. The
 * forward reading also asks that it was not taken for several objects
 * side by side (objects == 1), as its refusal does; the readings both
 * ways only ask whether to read again. */
static int taken_for_several(int moved, const elfm_calib_sweep_fit *f)
{
  return moved == 0 && f->several_share >= ELFM_CALIB_SWEEP_SEVERAL;
}

/* A one-way sweep read both ways for its focus: forwards, and played
 * backwards (elfm_events_reverse into a temporary file, removed after),
 * each fitted from the same start on the integral started empty unless
 * --integral-start-ms was given (why: docs/recon.md "A one-way sweep read
 * both ways"). 1 with *fw and *back filled; on any failure a note on
 * stderr and 0: the focus of the fit stands alone. */
static int sweep_both_ways(refine_ctx *c, const elfm_calib *start, elfm_calib_sweep_fit *fw,
                           elfm_calib_sweep_fit *back)
{
  const refine_opts *o = c->o;
  elfm_recon_options ro = o->recon;
  if (ro.framer.repr == ELFM_REPR_INTEGRAL && !o->istart_given) ro.integral_start_us = 0;
  char path[4096];
  elfm_error err;
  elfm_error_clear(&err);
  if (!cli_temp_path(path, sizeof path, "eventlfm-sweep-backwards")) {
    if (!o->quiet) fprintf(stderr, "calib refine: no temporary file for the sweep read backwards (TMPDIR?): "
                           "its focus read forwards alone\n");
    return 0;
  }
  /* a file without a geometry (CSV) gets the sensor's, which the passes
   * ask of the copy (not the smallest holding its events) */
  elfm_reader_options rd = o->recon.reader;
  if (rd.width == 0 && rd.height == 0) {
    rd.width = start->sensor_width_px;
    rd.height = start->sensor_height_px;
  }
  elfm_status st = elfm_events_reverse(o->events, &rd, o->recon.from_us, o->recon.to_us, path, NULL, &err);
  double shift[2 * ELFM_MAX_VIEWS];
  int moved_fw = 0, moved_back = 0;
  size_t frames = 0;
  /* a reading taken for several objects is made again through the 3 x 3
   * median, as the forward reading is (refine_sweep_step): sensor noise,
   * whose polarities swap backwards */
  for (int again = 0; again < 2 && st == ELFM_OK; again++) {
    elfm_calib cal = *start;
    st = sweep_pass(c, &ro, &cal, shift, &moved_fw, fw, &frames, &err);
    cal = *start;
    if (st == ELFM_OK) {
      c->events = path;
      st = sweep_pass(c, &ro, &cal, shift, &moved_back, back, &frames, &err);
      c->events = o->events;
    }
    if (st != ELFM_OK) break;
    const int noise = taken_for_several(moved_fw, fw) || taken_for_several(moved_back, back);
    if (!noise || o->median_given || ro.median != 0) break;
    ro.median = 3;
  }
  remove(path);
  if (st != ELFM_OK && !o->quiet) {
    char buf[1200];
    fprintf(stderr, "calib refine: the sweep read both ways: %s: its focus read forwards alone\n",
            elfm_error_format(&err, buf, sizeof buf));
  } else if ((moved_fw == 0 || moved_back == 0) && !o->quiet) {
    const elfm_calib_sweep_fit *f = moved_fw == 0 ? fw : back;
    fprintf(stderr, "calib refine: the sweep read %s on the integral started empty fitted no views (%d frames told "
            "the depth; a median %.2f of the frames held two spots or more): its focus read forwards alone\n",
            moved_fw == 0 ? "forwards" : "backwards", f->frames_used, f->several_share);
  }
  return st == ELFM_OK && moved_fw > 0 && moved_back > 0;
}

/* --sweep: the recording is one object swept through z, whose images the
 * coarse step's refocused peaks would not find from centres a few pixels
 * off (from 2.3 px RMS off it took noise for a turn of -3.3 degrees and
 * fitted nothing). Each view's images are found frame by frame and the
 * centres fitted to them (elfm_calib_sweep_*, recon/calib_sweep.c),
 * in place of the turn's search and the coarse step; on the integral,
 * which shows a slow object (choose_repr), unless the frames are given. */
int refine_sweep_step(refine_ctx *c, elfm_calib *cal, refine_opts *o, double *total, elfm_error *err)
{
  if (o->repr_auto) {
    o->recon = o->recon_integral;
    o->threshold = refine_integral_threshold(o);
    if (refine_set_threshold(c, cal, o->threshold, err) != ELFM_OK) return cli_fail(C, err);
  }
  double shift[2 * ELFM_MAX_VIEWS];
  int moved = 0;
  elfm_calib_sweep_fit fit;
  size_t frames = 0;
  const elfm_calib start = *cal;
  if (sweep_pass(c, &o->recon, cal, shift, &moved, &fit, &frames, err) != ELFM_OK) return cli_fail(C, err);
  /* Sensor noise (background activity, 10 Hz a pixel where the
   * simulator's is 2) puts spots beside a faint, far-defocused image in
   * most frames: taken for several objects that do not move together.
   * The 3 x 3 median takes out lone noise pixels and keeps an image of
   * several: read again through it, for the passes too, unless --median
   * was given (docs/recon.md "A one-way sweep read both ways") */
  if (taken_for_several(moved, &fit) && fit.objects == 1 && !o->median_given && o->recon.median == 0) {
    if (!o->quiet)
      fprintf(stderr, "calib refine: a median %.2f of the frames hold two spots or more in a view, not moving as "
              "one pattern: noise? read again through the 3 x 3 median filter (--median 3)\n", fit.several_share);
    /* kept only if it fits: else the first reading is what is refused */
    elfm_recon_options ro = o->recon;
    ro.median = 3;
    elfm_calib m = start;
    double shift_m[2 * ELFM_MAX_VIEWS];
    int moved_m = 0;
    elfm_calib_sweep_fit fit_m;
    size_t frames_m = 0;
    if (sweep_pass(c, &ro, &m, shift_m, &moved_m, &fit_m, &frames_m, err) != ELFM_OK) return cli_fail(C, err);
    if (moved_m > 0) {
      o->recon.median = 3;
      *cal = m;
      memcpy(shift, shift_m, sizeof shift);
      moved = moved_m;
      fit = fit_m;
      frames = frames_m;
    }
  }
  if (taken_for_several(moved, &fit) && fit.objects == 1)
    return cli_message(C, CLI_FAIL, "%s: several objects in the views (a median %.2f of the frames hold two "
                       "spots or more), and they do not move as one pattern: %.2f of the frames matched it, "
                       "0.5 or more needed. Is one object, or several side by side, swept together through z "
                       "in %" PRId64 "..%" PRId64 " us?", o->events, fit.several_share, fit.pattern_share,
                       o->recon.from_us, o->recon.to_us);
  if (moved == 0 && fit.off_grid_px > ELFM_CALIB_SWEEP_OFF_GRID_PX && fit.off_grid_view >= 0)
    return cli_message(C, CLI_FAIL, "%s: the centres fitted to the sweep's images lie off the lenslets' grid: "
                       "view (%+d, %+d) %.1f px from the grid of the fitted views (%g at most). Objects taken "
                       "for each other (%d side by side)? A sweep of fewer objects, or of one, fits",
                       o->events, cal->views[fit.off_grid_view].i, cal->views[fit.off_grid_view].j,
                       fit.off_grid_px, ELFM_CALIB_SWEEP_OFF_GRID_PX, fit.objects);
  if (moved == 0)
    return cli_message(C, CLI_FAIL, "%s: the sweep's images fit too few views or frames to fit the centres to "
                       "(%d frames of %zu told the depth; the views' median share of their spots near the fit "
                       "%.2f, 0.5 or more needed, and %d images in a view): is one object, or several side by "
                       "side, swept together through z in %" PRId64 "..%" PRId64 " us?%s%s%s", o->events,
                       fit.frames_used, frames, fit.agree, o->min_points, o->recon.from_us, o->recon.to_us,
                       o->recon.framer.repr == ELFM_REPR_INTEGRAL ? "" : " On --repr ",
                       o->recon.framer.repr == ELFM_REPR_INTEGRAL ? "" : cli_repr_name(o->recon.framer.repr),
                       o->recon.framer.repr == ELFM_REPR_INTEGRAL
                           ? ""
                           : ", a slow object shows only where it moved: the integral, --sweep's default "
                             "without --repr, shows it whole");
  double rms, worst;
  refine_add_moves(c->nv, shift, total, &rms, &worst);
  if (!o->quiet) {
    int n_placed = 0;
    for (int v = 0; v < c->nv; v++) n_placed += fit.placed[v];
    char several[160] = "";
    if (fit.objects > 1)
      snprintf(several, sizeof several, " (%d objects side by side, %.1f um apart in depth at most, their "
               "pattern matched in a median %.2f of the frames)", fit.objects, fit.depth_um, fit.pattern_share);
    fprintf(stderr, "calib refine: the sweep's views, frame by frame%s: %d of %zu frames told the depth; "
            "%d of %d views fitted to their images (%.2f px RMS from the fit, a median %.2f of their spots "
            "near it, within %.2f px of their grid), %d set on the others' grid; moves RMS %.3f px, largest "
            "%.3f px\n", several, fit.frames_used, frames, moved, c->nv, fit.rms_px, fit.agree, fit.off_grid_px,
            n_placed, rms, worst);
  }
  /* a sweep up and down gave each way's focus; one way, it is read both
   * ways, unless the focus is kept */
  elfm_calib_sweep_fit fw, back;
  const int one_way = !(isfinite(fit.focus_up_um) && isfinite(fit.focus_down_um));
  const int both = one_way && !o->keep_focus && sweep_both_ways(c, &start, &fw, &back);
  return sweep_finish(cal, &start, &fit, both ? &fw : NULL, both ? &back : NULL, o->events, o->sweep_speed,
                      o->keep_focus, o->keep_scale, o->quiet);
}
