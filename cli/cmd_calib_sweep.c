/* cmd_calib_sweep.c — what `calib refine --sweep` makes of its fit besides
 * the centres (cmd_calib_refine.c): the focal plane where the object was
 * in focus, then the relay's magnification from the views' grid, and the
 * depth scale from the piezo's speed. */
#include <math.h>
#include <stdio.h>

#include "cli.h"

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
 * longer than the optics' put it 21 um off. Nearer than FOCUS_TOL_UM the
 * sweep does not tell it better than the calibration has it: 20 simulated
 * one-way sweeps on the 5 x 5 array put it -1.95..+1.91 um from the
 * truth's (3 x 3 and 7 x 7: +0.6..+3.6), mostly on the side the bead went
 * to; up and down, each way fitted alone, -0.99..+0.90 (docs/recon.md "The
 * focal plane from a sweep"). 1 when it moved the focal plane. */
#define FOCUS_TOL_UM 2.0
static int sweep_focus(elfm_calib *cal, const elfm_calib_sweep_fit *fit, int keep, int quiet)
{
  const double z = fit->focus_um;
  if (!isfinite(z)) {
    if (!quiet)
      fprintf(stderr, "calib refine: the sweep's images were strongest at no depth it went through and out of "
              "both ways: the focal plane kept\n");
    return 0;
  }
  const int move = !keep && fabs(z) > FOCUS_TOL_UM;
  if (move) elfm_calib_move_focus(cal, z);
  char ways[96] = "";
  if (isfinite(fit->focus_up_um) && isfinite(fit->focus_down_um))
    snprintf(ways, sizeof ways, " (the mean of the way up's %+.2f and the way down's %+.2f)", fit->focus_up_um,
             fit->focus_down_um);
  if (!quiet) {
    fprintf(stderr, "calib refine: the sweep's images were strongest at z %+.2f um of the fitted depths%s: ", z, ways);
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

int calib_sweep_finish(elfm_calib *cal, const elfm_calib *start, const elfm_calib_sweep_fit *fit, const char *events,
                       double speed_um_per_ms, int keep_focus, int keep_scale, int quiet)
{
  const int moved = sweep_focus(cal, fit, keep_focus, quiet);
  const double k = sweep_relay(cal, start, moved, keep_scale, quiet);
  return sweep_scale(cal, fit, k, events, speed_um_per_ms, quiet);
}
