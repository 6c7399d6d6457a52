/* elfm_smooth.h — Ceres-smoothed trajectories with a motion model chosen
 * per track (the C interface of the C++ bridge tracker/smooth.cc).
 *
 * DATA TERM. Each point i contributes r_i = (p(t_i) - x_i) / sigma_i per
 * axis (anisotropic localisation uncertainty), under a robust loss on
 * |r_i|^2 (Huber or Cauchy, scale `loss_scale` in units of sigma) so that
 * outliers (a wrong link, a ghost) pull little.
 * MODELS.
 *   constant velocity      p(t) = p0 + v t                         (6 parameters)
 *   constant acceleration  p(t) = p0 + v t + a t^2 / 2             (9 parameters)
 *   smoothing spline       one position per time; prior on the acceleration
 *       sum_k lambda * hbar_k * |a_k / sigma_ref|^2, a_k the second divided
 *       difference at state k and hbar_k the mean of its two intervals (so
 *       the prior approximates lambda * integral |a|^2 dt and scales with the
 *       frame interval); lambda in ms^3. Without a given weight, lambda is
 *       chosen by generalised cross-validation (GCV) over a grid
 *       10^-4 .. 10^8 ms^3; its effective degrees of freedom (edf, the trace
 *       of the hat matrix) come from a banded selected inverse.
 *       With spline_order 3 the prior may also leave a turn rate alone
 *       (spline_omega_rad_per_ms: p''' + omega^2 p', an L-spline).
 *   AUTO chooses the model with the lowest BIC = sum_i rho(|r_i|^2) +
 *   k ln(3 n) (k = 6, 9, or 3 edf); ties go to the simpler model.
 * NOISE. Without per-point sigmas, sigma per axis is estimated from the
 * data: 1.4826 MAD of the normalised second differences of consecutive
 * points (a straight or slowly curving track has none), at most that of
 * the fourth differences / 0.6 (a path turning far between frames fills
 * its second differences; smooth_noise.c), floored at
 * min_sigma_*_um. With fewer than 3 second differences (under 5 points)
 * the noise is unknown: the fit uses the floors, and the uncertainties it
 * reports are NaN (elfm_smooth_noise_known).
 * NUMERICS. Times are taken relative to a reference inside the track (int64
 * difference, then double ms) and positions relative to their mean, so a
 * constant offset in time (absolute times ~1e12 us) or space changes
 * nothing. Tracks of one point, or all points at one time, are STATIC
 * (velocity 0, its uncertainty NaN = undetermined); two distinct times allow
 * only constant velocity, three also constant acceleration, four or more
 * also the spline. Non-finite input is ELFM_ERR_NUMERIC.
 * Solver: Ceres (C++ API), DENSE_QR for the parametric models, sparse
 * normal Cholesky (banded problem) for the spline unless `solver` says
 * dense; Ceres prints nothing.
 */
#ifndef ELFM_SMOOTH_H
#define ELFM_SMOOTH_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_recon.h"
#include "elfm_tracks.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum elfm_robust_loss {
  ELFM_LOSS_NONE = 0,
  ELFM_LOSS_HUBER,
  ELFM_LOSS_CAUCHY
} elfm_robust_loss;

typedef enum elfm_smooth_solver {
  ELFM_SOLVER_AUTO = 0,  /* dense for small problems, sparse for the spline */
  ELFM_SOLVER_DENSE,
  ELFM_SOLVER_SPARSE
} elfm_smooth_solver;

typedef struct elfm_smooth_options {
  elfm_motion_model model;      /* AUTO by default */
  elfm_robust_loss loss;        /* HUBER */
  double loss_scale;            /* 3 (sigma units of the 3D residual norm) */
  /* An outlier (elfm_smooth_info.n_outliers) also lies this far from the
   * fit, um with z counted / 4 (SPEC's distance); 0 (default): no floor.
   * Why: the noise the points' second differences give is small on a
   * short track, or where the errors wander together from point to point,
   * and a bead's own points 0.5 um off then lay 4-5 sigma out; track
   * dropped whole tracks of one bead as "not one object" (4 of the 6 it
   * dropped on flow_random, blink_moving; track: 1.5 um). */
  double outlier_min_um;
  double spline_weight_ms3;     /* lambda; <= 0: chosen by GCV */
  /* GCV's price per effective parameter: lambda minimises
   * n RSS / (n - gcv_gamma x edf)^2, >= 1. 1 (default) is the classical
   * GCV, right for independent errors; it undersmooths when the errors
   * are correlated from frame to frame, as an event camera's detections
   * are (a time surface shares events between frames: on flow their lag-1
   * autocorrelation is 0.54-0.58 laterally). 1.4 (`eventlfm track`; 5 on
   * the integral, whose frames share most of their events) is the
   * modified GCV of Cummins, Filloon & Nychka (2001) and Kim & Gu (2004).
   * test_smooth 9b; docs/tracker.md "Smoother", "The integral's spline
   * weight". */
  double gcv_gamma;
  /* What the smoothing spline's prior penalises: 2 (default) the
   * acceleration, integral |a|^2 dt, whose stiff limit is a straight line;
   * 3 the jerk, integral |da/dt|^2 dt, whose stiff limit is a constant
   * acceleration, so an object turning at constant speed is pulled less
   * inside its curve (not at all with spline_omega_rad_per_ms at its
   * rate). */
  int spline_order;
  /* With spline_order 3: the prior penalises p''' + omega^2 p' instead of
   * p''' (an L-spline), which is 0 on a circle travelled at omega rad per
   * ms in any plane and position, so such a turn is not pulled in (the
   * discrete rows use 2 sin(omega h / 2) / h for omega over an interval h,
   * which makes them 0 on the sampled circle). 0 = off (default). */
  double spline_omega_rad_per_ms;
  /* elfm_track_smooth only, with spline_order 3: a track the spline fits
   * is fitted again with spline_omega_rad_per_ms = the median turn rate of
   * the first fit's velocity (the angle between the velocities of
   * neighbouring frames over their interval, where both exceed 0.5 um/ms;
   * at least 5 of them), its weight chosen again by GCV unless
   * spline_weight_ms3 is given; with a motion bias, that fit's velocity
   * then gives the bias once more and the points are fitted again (same
   * prior and weight). Why: a flow bead circles at 0.2-0.4 rad/ms, and
   * the jerk prior pulls every turn in; the weight GCV can afford without
   * that pull is larger. Flow 100 ms seeds 1-20 alpha 0.8671 -> 0.8749,
   * 0.8768 with the bias once more (docs/tracker.md "Splines along the
   * turn"). 0 = off (default; track: 1). */
  int spline_turn;
  elfm_smooth_solver solver;
  int max_iterations;           /* Ceres iterations, 50 */
  /* 1: the fits as the reweighted linear fits (IRLS) leave them, without
   * Ceres's polish (a fit whose result only feeds another:
   * elfm_track_smooth's first fits, when a last one follows). 0 (default):
   * Ceres polishes the fits that could be chosen. */
  int irls_only;
  double min_sigma_xy_um;       /* floors of the estimated noise: 0.02 um */
  double min_sigma_z_um;        /* and 0.08 um (kz = 4 times the lateral) */
  int allow_spline;             /* AUTO may pick the spline (1); 0 for rigid stage motion */
  /* elfm_track_smooth only: a point the view fit found where no peak
   * stood out (elfm_detection.view_fit) counts as this many times noisier than the
   * track's estimated noise, which its peaks keep (1.5; 1 = all points
   * alike). */
  double view_fit_sigma_factor;
  /* elfm_track_smooth only: each point's sigma is also scaled by (its
   * fit_sd_px / the median over the track's points that have one)^power,
   * within [0.5, 3] (a guard: a fit of a few views can have a residual of
   * ~0), so that the points whose views agreed less count less. fit_sd_px is
   * the view fit's residual RMS over sqrt(views agreeing) (elfm_detection);
   * points without one, and tracks with fewer than 3 such points, keep
   * factor 1. Why: on flow, within |z| 30-60 um, the raw points' RMSE by
   * quartile of fit_sd_px is 0.44 / 0.54 / 0.63 / 0.80 um laterally and 0.62
   * / 0.83 / 0.99 / 1.55 um in z (seeds 1-4). 0 = off (default; track: 1,
   * 0 with --repr integral; docs/tracker.md "Smoother"). */
  double fit_sd_power;
  /* Motion bias of the detections, corrected by elfm_track_smooth only
   * (0 and 0 = off, the default). A detection made from ON events lies
   * ahead of the object by a distance (the ON events crowd on its leading
   * half) and shows where it was some time before the frame's t_us (sensor
   * latency plus the mean age of the events the frame weights). The model
   * (elfm_motion_bias): in an image moving at w the image centre is off by
   * b(w) = lead x w / max(|w|, 0.5 um/ms) - delay x w (the lead fades out
   * below 0.5 um/ms, where the direction of motion is noise).
   *  - Without views (motion_n_views 0) that applies to the lateral
   *    position, w = the lateral velocity; z is left alone.
   *  - With the views' disparities g_v (lateral um of image shift per um of
   *    z, motion_view_g) the detection is taken to be the equal-weight
   *    least-squares fit of the 25 view images, as the view fit is: view v's
   *    image moves at w_v = v_xy + v_z g_v, each image is off by b(w_v),
   *    and the fit's bias is the least-squares solution of b(w_v) = dp +
   *    dz g_v over the views (dz = sum (b_v - mean b).(g_v - mean g) /
   *    sum |g_v - mean g|^2, dp = mean b - dz mean g). A bead moving in z
   *    thus shows its lead in z too, and the delay as -delay x v_z.
   * elfm_track_smooth fits the track, moves each point by -b of the fitted
   * velocity there, and fits again with the first fit's model and spline
   * weight. The track's points (pts) keep the detections as measured. */
  double motion_lead_um;
  double motion_delay_us;
  /* Below this image speed (um/ms) the lead fades out in proportion (the
   * direction of motion is noise there): 0.5 by default; slow samples
   * whose smoothed velocity still has a direction lower it (`track --repr
   * integral`: 0.05, worm neurons at 0.05-0.3 um/ms). */
  double motion_lead_fade_um_per_ms;
  /* Slower images lead further than the line above says: below
   * motion_slow_um_per_ms the lead grows by motion_slow_lead_ms x (that
   * speed - |w|) um (it fades with the lead below the fade speed). Why: on
   * the ON time surface the error along the motion, binned by speed, bends
   * away from lead - delay x |w| below ~3 um/ms, by 0.35-0.5 um at 1 um/ms,
   * for 0.5 and 1 ms windows and tau 1 and 2 ms alike (docs/tracker.md "The
   * lead of slow beads"). 0 = off (the default; track: 0.17 ms below 3
   * um/ms with its own lead and delay). */
  double motion_slow_lead_ms;
  double motion_slow_um_per_ms;
  /* 1: the bias along the fitted path (0 = off, the default; track: on).
   * The image shows the object where it was motion_delay_us ago, ahead
   * along its motion then: each view's lead lies along its velocity at
   * that time (the fitted velocity there), and the way back is the mean
   * of the velocities then and now times the delay. On a straight path
   * that is the model above; on a turn the earlier motion points outward
   * of the present one, and the lead with it: raw detections of
   * flow_random lie 0.2-0.6 um outward of beads turning at 1-2 um/ms^2
   * below 2 um/ms, about lead x delay x turn rate (docs/tracker.md "The
   * lead along the path"). Without a delay (or with one below 0) it is
   * the model above. */
  int motion_along_path;
  int motion_n_views;                       /* 0: lateral model only */
  double motion_view_g[ELFM_MAX_VIEWS][2];  /* (gx, gy) per view, um per um of z */
  /* elfm_track_smooth only: the run's frame times (elfm_tracks.h; borrowed,
   * may be NULL). A gap frame's time comes from here when recorded, else
   * it is interpolated between the gap's ends (exact for evenly spaced
   * frames). */
  const elfm_frame_times *frame_times;
} elfm_smooth_options;

void elfm_smooth_options_default(elfm_smooth_options *o);
/* The views' disparities of calibration c into o->motion_view_g (the views'
 * model of the motion bias above): g_v = (dx, dy)_px_per_um x um_per_px. */
void elfm_smooth_options_set_views(elfm_smooth_options *o, const elfm_calib *c);

typedef struct elfm_smooth_info {
  elfm_motion_model model;      /* model used */
  double spline_weight_ms3;     /* lambda used (SPLINE) */
  double edf;                   /* effective parameters per axis (mean over axes) */
  double bic[5];                /* by elfm_motion_model index; NaN where not fitted */
  double sigma_um[3];           /* noise per axis used (estimated or median given) */
  double accel_um_per_ms2[3];   /* CONST_ACCEL: the fitted acceleration; else 0 */
  int n_outliers;               /* points beyond twice the loss scale (where Huber's weight
                                   falls below 1/2), whichever the loss, and farther than
                                   outlier_min_um from the fit */
  int ceres;                    /* 1: Ceres polished the fit used; 0: the reweighted
                                   linear fits alone (irls_only; the spline under the
                                   plain loss, a linear fit; a static track) */
} elfm_smooth_info;

/* Fit n points (t_us non-decreasing; xyz_um n x 3; sigma_um n x 3 or NULL
 * to estimate) and evaluate at nq query times q_t_us (non-decreasing, any
 * times for the parametric models; the spline puts a state at every query
 * time and every data time). Outputs are nq x 3, caller-allocated; any
 * output pointer may be NULL. info may be NULL. Allocates scratch per call
 * (a track is smoothed once, when it ends). */
elfm_status elfm_smooth_fit(const elfm_smooth_options *o, size_t n, const int64_t *t_us,
                            const double *xyz_um, const double *sigma_um, size_t nq,
                            const int64_t *q_t_us, double *pos_um, double *vel_um_per_ms,
                            double *pos_sd_um, double *vel_sd_um_per_ms, elfm_smooth_info *info,
                            elfm_error *err);

/* Whether n points at these times tell their own noise: 3 or more second
 * differences of distinct times (5 points, or more with repeated times).
 * Else the estimate below is only its floors (min_sigma_*_um), and
 * elfm_smooth_fit without sigmas and elfm_track_smooth report the
 * uncertainties as NaN (undetermined), not as ones that small. */
int elfm_smooth_noise_known(size_t n, const int64_t *t_us);

/* The noise per axis elfm_smooth_fit estimates when given no sigmas
 * (NOISE above), for a caller that weights some points differently. */
elfm_status elfm_smooth_estimate_noise(const elfm_smooth_options *o, size_t n,
                                       const int64_t *t_us, const double *xyz_um,
                                       double sigma_um[3], elfm_error *err);

/* The motion bias b (um, x y z) of a detection of an object moving at v
 * (um/ms) under o's model (above). Zeros when the lead and delay are 0. */
void elfm_motion_bias(const elfm_smooth_options *o, const double v_um_per_ms[3], double b_um[3]);
/* Smooth a finished track over its span (one state per frame first..last;
 * t_us of gap frames interpolated linearly between the neighbouring real
 * points) and store the result in the track (elfm_tracks.h), replacing
 * any earlier one. The track keeps ownership of the arrays. With a motion
 * bias in o (above), a track of 3 or more points is fitted twice. */
elfm_status elfm_track_smooth(elfm_track *t, const elfm_smooth_options *o, elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
