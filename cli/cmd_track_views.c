/* cmd_track_views.c — does the calibration fit the recording? (cmd_track.h,
 * "the views' check")
 *
 * A calibration that does not fit makes track fail quietly: on flow turned
 * by 1 degree against an aligned calibration, 95 % of the peaks failed the
 * view-support test, the first run judged them faint and fast and started
 * again with a blur and shorter windows, and alpha was 0.02 (docs/recon.md
 * "A lens array turned against the sensor"). What shows it is the view fit
 * each peak already gets: a view whose centre is off leaves its images off
 * the fitted point by the same amount in every fit (up to the fit's outlier
 * limit, 1.5 px), and a view off by more is left out of most fits
 * (docs/recon.md "Does the calibration fit?" has the measurements). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd_track.h"

/* Judged only over this many view fits or more */
#define VIEWS_MIN_FITS 100
/* A view's mean miss beyond this is off. With the right centres the means
 * stay under 0.11 px on 44 simulated recordings of most scenes (the
 * simulated images' own bias), 0.27 px for a stage moving 2 mm/s in z
 * (its images' lead along their disparities, beyond what the gauge takes
 * out); centres moved 0.3 px RMS at random give 0.45-0.48 px, which flow
 * does not yet feel (docs/recon.md), 1 px RMS 0.85-0.89 and 0.09 of alpha. */
#define VIEWS_MISS_PX 0.4
/* A view kept in less than this share of the median view's fits is off (a
 * view far off is left out of nearly every fit: 4-7 % against 87-91 %).
 * Judged among the views wholly on the sensor (VIEWS_ON_SENSOR) only: a
 * view partly off it sees fewer of the objects, and a 7 x 7 array's
 * corners on the EVK4 are off it altogether (kept in no fit at all). */
#define VIEWS_SHARE_RATIO 0.5
#define VIEWS_ON_SENSOR 0.99
/* The median view kept in fewer fits than this: the views disagree (an
 * aligned calibration on a lens array turned 1 degree: 28-31 %; the right
 * ones 53-100 %, the least with a bright background) */
#define VIEWS_MEDIAN_SHARE 0.4
/* Or the view-support test let almost no peak through: at least this share
 * of VIEWS_MIN_PEAKS peaks or more rejected (turned 3 degrees: 98-99 %,
 * turned 1 degree 95-97 %; the right calibrations at most 93 %, flow in a
 * strong haze, and 90 % for a worm on 3 x 3 views). With the test off
 * (--view-support 0) the view fits say it (turned 3 degrees: the median
 * view in 27 % of them). */
#define VIEWS_MAX_REJECTED 0.97
#define VIEWS_MIN_PEAKS 500
/* A view's mean miss is judged from this many fits that kept it */
#define VIEWS_MIN_KEPT 50

void track_views_add(struct slot_peaks *sp, const elfm_calib *calib, const double xyz_um[3],
                     const double *miss_px, const double *weight)
{
  for (int v = 0; v < calib->n_views; v++) {
    if (!(weight[v] > 0)) continue;
    double *s = sp->view_miss + TRACK_VIEW_SUMS * v, u, w;
    elfm_calib_project(calib, v, xyz_um[0], xyz_um[1], xyz_um[2], &u, &w);
    u -= calib->views[v].cx_px;
    w -= calib->views[v].cy_px;
    s[0] += miss_px[2 * v];
    s[1] += miss_px[2 * v + 1];
    s[2] += 1;
    s[3] += u;
    s[4] += w;
    s[5] += u * u + w * w;
  }
  sp->fits++;
}

void track_views_merge(track_ctx *c, int slot)
{
  struct slot_peaks *sp = &c->sp[slot];
  for (int k = 0; k < TRACK_VIEW_SUMS * c->calib->n_views; k++) c->view_miss[k] += sp->view_miss[k];
  c->view_fits += sp->fits;
  c->view_tries += sp->tries;
}

static int cmp_double(const void *a, const void *b)
{
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A bead moving in z leads (or trails) its image in each view by about the
 * same distance along that view's disparity, whatever the disparity's
 * length (the ON events fire on the image's leading half; the integral's
 * leak trails it): a move of the same length along each view's disparity,
 * which the z of the point's fit takes up only in proportion to the
 * disparities, leaving the rest in the inner views. Taken out together
 * with the gauge (alternating projections, which converge on the joint
 * least-squares fit). */
static void lead_clear(int nv, const int *use, const double *du, const double *dw, double *mu,
                       double *mw)
{
  double gu[ELFM_MAX_VIEWS], gw[ELFM_MAX_VIEWS]; /* each disparity's direction (0: none) */
  int n = 0;
  for (int v = 0; v < nv; v++) {
    const double g = hypot(du[v], dw[v]);
    const int on = use[v] && g > 0;
    gu[v] = on ? du[v] / g : 0;
    gw[v] = on ? dw[v] / g : 0;
    n += on;
  }
  if (n == 0) return;
  for (int it = 0; it < 8; it++) {
    double a = 0;
    for (int v = 0; v < nv; v++) a += mu[v] * gu[v] + mw[v] * gw[v];
    a /= n;
    for (int v = 0; v < nv; v++) {
      mu[v] -= a * gu[v];
      mw[v] -= a * gw[v];
    }
    elfm_calib_gauge_clear(nv, use, du, mu);
    elfm_calib_gauge_clear(nv, use, dw, mw);
  }
}

void track_views_judge(const track_ctx *c, track_views_check *out)
{
  const int nv = c->calib->n_views;
  memset(out, 0, sizeof *out);
  out->fits = c->view_fits;
  out->tries = c->view_tries;
  out->worst = out->least = -1;
  out->worst_miss_px = out->worst_u_px = out->worst_w_px = NAN;
  out->least_share = out->median_share = NAN;
  out->rejected = c->n_support_rejected;
  const int64_t peaks = c->n_support_rejected + c->view_tries;
  out->few_placed =
      peaks >= VIEWS_MIN_PEAKS && (double)c->n_support_rejected >= VIEWS_MAX_REJECTED * (double)peaks;
  out->off = out->few_placed;
  if (c->view_fits < VIEWS_MIN_FITS || nv < 2) return;
  out->judged = 1;
  double share[ELFM_MAX_VIEWS], mu[ELFM_MAX_VIEWS] = {0}, mw[ELFM_MAX_VIEWS] = {0};
  double du[ELFM_MAX_VIEWS], dw[ELFM_MAX_VIEWS];
  int use[ELFM_MAX_VIEWS] = {0}, n_whole = 0, n_use = 0;
  for (int v = 0; v < nv; v++) {
    const double *s = c->view_miss + TRACK_VIEW_SUMS * v, kept = s[2];
    out->share[v] = kept / (double)c->view_fits;
    if (elfm_calib_view_on_sensor(c->calib, v) >= VIEWS_ON_SENSOR) {
      share[n_whole++] = out->share[v];
      if (out->least < 0 || share[n_whole - 1] < out->least_share) {
        out->least = v;
        out->least_share = share[n_whole - 1];
      }
    }
    /* A view whose images stayed in one place (the central view of a bead
     * swept through z) has a miss that follows wherever its centre is put,
     * and tells nothing of it: not judged (calib refine sets such a view on
     * the others' grid; elfm_calib.h). One bead swept at 1 mm/s drew the
     * note on that view alone (0.43 px), its images within 0.1 px. */
    const double mean_u = kept > 0 ? s[3] / kept : 0, mean_w = kept > 0 ? s[4] / kept : 0;
    out->spread_px[v] = kept > 0 ? sqrt(fmax(0, s[5] / kept - mean_u * mean_u - mean_w * mean_w)) : NAN;
    out->still[v] = kept >= VIEWS_MIN_KEPT && out->spread_px[v] < ELFM_CALIB_STILL_PX;
    use[v] = kept >= VIEWS_MIN_KEPT && !out->still[v];
    n_use += use[v];
    if (use[v]) {
      mu[v] = s[0] / kept;
      mw[v] = s[1] / kept;
    }
    du[v] = c->calib->views[v].dx_px_per_um;
    dw[v] = c->calib->views[v].dy_px_per_um;
  }
  /* The two moves of all views no fit can tell from the point's own (all
   * alike: x or y; in proportion to the disparities: z), taken out as calib
   * refine takes them out. Beads moving in z lead their images along their
   * disparities, a pattern in proportion to them, not a view off (a stage
   * moving 2 mm/s in z: the worst view 0.53 px with it, 0.27 px without),
   * and by about one length in every view, which lead_clear takes out (one
   * bead swept through z: 0.46 -> 0.31 px; docs/recon.md "Does the
   * calibration fit?"). */
  elfm_calib_gauge_clear(nv, use, du, mu);
  elfm_calib_gauge_clear(nv, use, dw, mw);
  lead_clear(nv, use, du, dw, mu, mw);
  for (int v = 0; v < nv; v++) {
    out->miss_px[v][0] = use[v] ? mu[v] : NAN;
    out->miss_px[v][1] = use[v] ? mw[v] : NAN;
  }
  /* (with fewer than 4 views to compare, the gauge's three moves leave
   * nothing to judge) */
  for (int v = 0; v < nv && n_use >= 4; v++) {
    if (!use[v]) continue;
    const double u = mu[v], w = mw[v];
    if (out->worst < 0 || hypot(u, w) > out->worst_miss_px) {
      out->worst = v;
      out->worst_miss_px = hypot(u, w);
      out->worst_u_px = u;
      out->worst_w_px = w;
    }
  }
  out->off = out->worst >= 0 && out->worst_miss_px > VIEWS_MISS_PX;
  if (n_whole >= 3) {
    qsort(share, (size_t)n_whole, sizeof *share, cmp_double);
    out->median_share =
        n_whole % 2 ? share[n_whole / 2] : 0.5 * (share[n_whole / 2 - 1] + share[n_whole / 2]);
    out->off |= out->least_share < VIEWS_SHARE_RATIO * out->median_share ||
                out->median_share < VIEWS_MEDIAN_SHARE;
  } else {
    out->least = -1;
    out->least_share = NAN;
  }
}

void track_views_note(const track_ctx *c)
{
  if (c->o->quiet) return;
  track_views_check k;
  track_views_judge(c, &k);
  if (!k.off) return;
  char what[320];
  if (k.few_placed) {
    snprintf(what, sizeof what, "the views agreed on %lld of %lld peaks (%lld failed the view-support "
             "test, %lld the view fit)", (long long)k.fits, (long long)(k.rejected + k.tries),
             (long long)k.rejected, (long long)(k.tries - k.fits));
  } else {
    char worst[160] = "", least[160] = "";
    if (k.worst >= 0 && k.worst_miss_px > VIEWS_MISS_PX) {
      const elfm_view *w = &c->calib->views[k.worst];
      snprintf(worst, sizeof worst, "; view (%+d, %+d)'s images lie (%+.2f, %+.2f) px off on average",
               w->i, w->j, k.worst_u_px, k.worst_w_px);
    }
    if (k.least >= 0) {
      const elfm_view *l = &c->calib->views[k.least];
      snprintf(least, sizeof least, "; view (%+d, %+d) takes part in %.0f %% of them (the median view "
               "%.0f %%)", l->i, l->j, 100 * k.least_share, 100 * k.median_share);
    }
    snprintf(what, sizeof what, "over %lld view fits%s%s", (long long)k.fits, worst, least);
  }
  fprintf(stderr, "eventlfm track: note: the calibration may not fit this recording: %s; eventlfm "
                  "calib refine fits the views to a recording of beads (docs/recon.md \"Does the "
                  "calibration fit?\")\n", what);
}
