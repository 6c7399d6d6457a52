/* elfm_analysis.h — what the tracks and volumes say about the experiment:
 * the stage velocity (all beads move together) and the resolution (FWHM of
 * isolated reconstructed beads; the paper: 3.9 um lateral, 21.0 um axial).
 */
#ifndef ELFM_ANALYSIS_H
#define ELFM_ANALYSIS_H

#include <stddef.h>

#include "elfm_recon.h"
#include "elfm_peaks.h"
#include "elfm_tracks.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Stage: each smoothed track's mean velocity, weighted by its number of real
 * points, averaged over tracks; a track of one frame, whose velocity is not
 * measured (elfm_track_velocity_known), is left out. spread = standard deviation across tracks
 * (unweighted). With a given stage velocity, rel_error = |v_mean - v_stage| /
 * |v_stage| and speed_rel_error = (|v_mean| - |v_stage|) / |v_stage|.
 * Acceleration: the slope in time of the smoothed velocity, fitted over
 * all tracks' rows together (a stage accelerates every bead alike, and a
 * track's rows alone span little of the ramp); its spread, the standard
 * deviation of the tracks' own slopes, over tracks of at least
 * ELFM_STAGE_ACCEL_MIN_ROWS rows (NaN with fewer than 2).
 * Pooled velocity: each track's mean velocity weighted, axis by axis, by
 * the precision of a slope fitted to it: the spread of its rows' times (sum
 * of (t - mean t)^2) over the variance of its real points about its
 * smoothed path on that axis (elfm_track_info.s_res2_um2, less their mean:
 * a constant lead does not count; at least ELFM_STAGE_POOL_MIN_VAR_UM2, a
 * 0.05 um scatter: a model through few points can fit them exactly),
 * as one velocity fitted to all tracks with an offset each would be by
 * weighted least squares. A short track then counts little (on a slow
 * stage, a bead crossing the field stop's edge gives a short, biased one;
 * docs/tracker.md "The stage's velocity pooled"), and so does a deep
 * bead's on z, whose points scatter over microns. Tracks of fewer than
 * ELFM_STAGE_POOL_MIN_POINTS real points are left out, unless no track has
 * as many (then the spread alone weighs). NaN when no track spans two
 * times. Stage 2.5 mm/s 200 ms seeds 1-11: the velocity's error 0.16 % ->
 * 0.07 % on the mean, 0.35 -> 0.11 % at most; 38 stages at 0.1-1.2 mm/s
 * 0.58 -> 0.36 % and 2.55 -> 2.11 % (docs/tracker.md "The stage's
 * velocity pooled"). */
#define ELFM_STAGE_ACCEL_MIN_ROWS 20
#define ELFM_STAGE_POOL_MIN_VAR_UM2 2.5e-3
#define ELFM_STAGE_POOL_MIN_POINTS 5
typedef struct elfm_stage_result {
  size_t n_tracks;
  double v_um_per_ms[3], v_sd_um_per_ms[3];
  double speed_um_per_ms, speed_sd_um_per_ms;
  double rel_error, speed_rel_error;   /* NaN without a stage velocity */
  double v_pooled_um_per_ms[3];
  double rel_error_pooled;             /* NaN without a stage velocity */
  double accel_um_per_ms2[3], accel_sd_um_per_ms2[3]; /* NaN: all rows at one time */
} elfm_stage_result;

/* Tracks that are not smoothed, or of one frame, are skipped; no track
 * left is ELFM_ERR_INVALID. stage_v may be NULL. */
elfm_status elfm_analysis_stage(const elfm_track_store *s, const double *stage_v_um_per_ms,
                                elfm_stage_result *out, elfm_error *err);
/* The same from the infos of tracks already freed (elfm_track_info_get). */
elfm_status elfm_analysis_stage_info(const elfm_track_info *ti, size_t n,
                                     const double *stage_v_um_per_ms, elfm_stage_result *out,
                                     elfm_error *err);

/* Resolution. For each detection of volume v that is isolated (no other
 * detection within isolation_um laterally), the full width at half maximum
 * along x, y and z through its peak voxel: the half-maximum crossings on
 * both sides, linearly interpolated between voxels (no shape assumed); a
 * profile that leaves the volume before halving is skipped. Writes up to
 * cap results; *n_out = number written. fwhm_xy = mean of x and y. */
typedef struct elfm_fwhm {
  double x_um, y_um, z_um;  /* where */
  double fwhm_xy_um, fwhm_z_um;
} elfm_fwhm;

elfm_status elfm_analysis_fwhm(const elfm_volume *v, const elfm_detection *d, int n,
                               double isolation_um, elfm_fwhm *out, int cap, int *n_out,
                               elfm_error *err);

/* Rigid shift between two frames' points: a stage moves every object by
 * the same vector, so of the candidate shifts b_j - a_i (every pair) the
 * stage's carries most points of a onto a point of b. For each candidate,
 * the points of a are matched in order to the first unused point of b
 * within tol_um (distance sqrt(dx^2 + dy^2 + (dz / kz)^2)); the candidate
 * with the most matches wins (the first one on ties), d_um is the mean
 * displacement of its matched pairs and *rms_um their RMS distance from
 * it, z / kz (NaN when none; rms_um may be NULL). Points are x, y, z
 * triples in um. O(na^2 nb^2): meant for a few dozen points a frame.
 * Non-finite coordinates, na or nb < 0, tol_um or kz not > 0:
 * ELFM_ERR_INVALID. Why a vote and not tracks: under an LED's pulses a
 * fast stage carries the beads 10-20 um between two pulses, farther than
 * the linker's gate, so few tracks grow long enough to show their common
 * velocity, while the two pulses' detections still overlap by that shift
 * (docs/tracker.md "A stage found by its frames' shift"). */
elfm_status elfm_analysis_shift_vote(const double *a_um, int na, const double *b_um, int nb,
                                     double tol_um, double kz, int *n_matched, double d_um[3],
                                     double *rms_um, elfm_error *err);

/* Median and spread (1.4826 MAD) of x[0..n-1] (reorders x). NaN when n = 0. */
void elfm_analysis_median(double *x, size_t n, double *median, double *spread);

#ifdef __cplusplus
}
#endif
#endif
