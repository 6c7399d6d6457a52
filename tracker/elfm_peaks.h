/* elfm_peaks.h — 3D peak detection in a reconstructed volume, with
 * sub-voxel refinement and the time-surface lag correction.
 *
 * A peak is a voxel above the threshold that is the maximum of an
 * anisotropic box around it (axial half-size ~5x the lateral one, because
 * the Fourier LFM's axial FWHM is ~5x its lateral FWHM: 21.0 vs 3.9 um).
 * Ties on plateaus are broken by voxel index, so a flat plateau yields one
 * peak. Peaks closer than min_separation_um (anisotropic distance
 * sqrt(dx^2+dy^2+(dz/kz)^2)) to a stronger one are dropped. Each axis is
 * then refined by a least-squares parabola over 2m+1 samples, fitted to
 * ln(value) (Gaussian) or to the value (quadratic); the parabola's
 * curvature gives the blob width sigma per axis.
 *
 * Usage: plan once per volume geometry, execute per volume:
 *   elfm_peaks *pk = elfm_peaks_create(&opt, w, h, nz, &err);
 *   elfm_peaks_detect(pk, vol, dets, cap, &n, &err);   // per frame, no malloc
 *   elfm_peaks_free(pk);
 */
#ifndef ELFM_PEAKS_H
#define ELFM_PEAKS_H

#include <stdint.h>

#include "elfm_recon.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One detected object in one frame. sigma_*_um is the fitted blob width
 * (Gaussian sigma) per axis, not the localisation uncertainty. */
typedef struct elfm_detection {
  int64_t frame;
  int64_t t_us;
  double x_um, y_um, z_um;
  double intensity;          /* refined peak value, volume units */
  double sigma_x_um, sigma_y_um, sigma_z_um;
  int weak;                  /* 1: above the low (hysteresis) threshold only */
  int deep_only;             /* 1: above the depth-scaled threshold (depth_range_um)
                                but not the plain absolute one */
  int view_fit;              /* 1: found by the view fit alone where no peak stood
                                out (elfm_refocus_localize from a track's prediction:
                                the guided search, gap filling); its sigmas are 0.
                                0: a peak above the threshold (placed by the peak fit
                                or, with `track --localize views`, the view fit) */
  double fit_sd_px;          /* the view fit's scatter (elfm_localize_result.sd_px: the
                                views' residual RMS over sqrt(views agreeing)), px; 0
                                when not placed by it */
  double width_um;           /* the peak's lateral width along its widest axis: the
                                second moment, in the peak's plane, of the values
                                above half the peak's (a window of +-6 voxels); 0
                                when not measured (view-fit points) */
  double nearest_um;         /* how far the nearest other detection of its frame
                                lies, in the linker's metric (dz / its kz); where
                                it is small, tracks may exchange objects. 0 when
                                not measured (set by `eventlfm track`) */
  int claims;                /* live tracks whose gate held it when it was linked
                                (elfm_link_step sets it): 2 or more, tracks
                                competed for it */
} elfm_detection;

typedef enum elfm_refine_mode {
  ELFM_REFINE_GAUSSIAN = 0,  /* parabola through ln(value): exact for a Gaussian */
  ELFM_REFINE_QUADRATIC,     /* parabola through the values */
  ELFM_REFINE_NONE           /* voxel centres */
} elfm_refine_mode;

typedef struct elfm_peaks_options {
  /* Threshold = max(absolute, relative * volume max, median + k_sigma *
   * robust sigma); a term <= 0 is off. Robust sigma = 1.4826 * MAD of a
   * strided sample of the volume (of its non-zero voxels when most voxels
   * are zero, as in thresholded time surfaces). */
  double absolute, relative, k_sigma;
  /* Depth-dependent absolute rule (0 = off): at depth z the absolute term is
   * max(absolute_min, absolute / (1 + (z / depth_range_um)^2)). Why: a
   * point's image in a view is a Gaussian of variance s0^2 + (a z)^2
   * (diffraction of the sub-aperture NA plus its geometric defocus disc), so
   * its peak - and the refocused peak, a mean over the views - falls as
   * 1 / (1 + (z / zr)^2) with zr = s0 / a; the floor keeps ghosts out. */
  double depth_range_um, absolute_min;
  /* Hysteresis (0 = off): peaks between this absolute value and the
   * threshold above are kept but marked weak; the linker lets a weak
   * detection continue a track, never start one (as Canny's edge
   * hysteresis): a bead dimmed by defocus stays tracked while ghosts of
   * the same brightness, which have no track to continue, are dropped. */
  double hysteresis_low;
  double radius_xy_um;       /* local-maximum box half-size, lateral (default 3 um ~ 0.8 FWHM) */
  double radius_z_um;        /* axial half-size (default 15 um = 5 x lateral) */
  double min_separation_um;  /* anisotropic, see above (default 4 um, the scoring gate) */
  double kz;                 /* axial scale of the anisotropic metric (4, SPEC §7) */
  elfm_refine_mode refine;
  int fit_half_xy, fit_half_z; /* m per axis: fit over 2m+1 voxels (1 and 3) */
} elfm_peaks_options;

void elfm_peaks_options_default(elfm_peaks_options *o);

typedef struct elfm_peaks elfm_peaks;

/* Detector with its workspace for volumes of w x h x nz voxels.
 * NULL (err filled) on bad options or no memory. Free with elfm_peaks_free. */
elfm_peaks *elfm_peaks_create(const elfm_peaks_options *o, int w, int h, int nz,
                              elfm_error *err);
void elfm_peaks_free(elfm_peaks *p);

/* Detect peaks in `v` (same geometry as at create) into out[0..cap-1],
 * strongest first; *n_out is the number written (the cap strongest when
 * there are more). Frame and t_us are copied from the volume. NaN voxels
 * are an error (ELFM_ERR_NUMERIC). Does not allocate. */
elfm_status elfm_peaks_detect(elfm_peaks *p, const elfm_volume *v, elfm_detection *out,
                              int cap, int *n_out, elfm_error *err);

/* Optional: how many views sample each voxel (w x h x nz, z-major like the
 * volume, as elfm_refocus_plan_views_at gives them) and the number of lit
 * views N. The volume is a mean over the sampling views, so where only n of
 * the N views sample a voxel a single view's image weighs N/n times more
 * and the noise of the mean grows as sqrt(N/n): a peak must there exceed
 * the threshold x (N/n)^exponent (1: ghosts of one or two views' images;
 * 0.5: noise; a real object is seen by all n and its mean does not depend
 * on n). Voxels no view samples never give a peak. The counts are copied;
 * NULL turns the rule off. ELFM_ERR_INVALID for N outside 1..255 or an
 * exponent outside 0..4, ELFM_ERR_NOMEM when the copy fails. */
elfm_status elfm_peaks_set_view_counts(elfm_peaks *p, const uint8_t *count, int n_views,
                                       double exponent, elfm_error *err);

/* Track-guided search: the largest voxel above min_value that is a local
 * maximum of its 3x3x3 neighbourhood within the ellipsoid of half-axes
 * radius_xy_um, radius_xy_um, radius_z_um around xyz_um, refined as in
 * elfm_peaks_detect into *out, marked weak; *found = 1, else 0. For a bead
 * whose track predicts it where the global threshold saw nothing (deep
 * beads fade to 25-55 on the time surface). Reads only the options of p
 * (safe next to a detect call on another thread), no allocation. */
elfm_status elfm_peaks_find_near(const elfm_peaks *p, const elfm_volume *v, const double xyz_um[3],
                                 double radius_xy_um, double radius_z_um, double min_value,
                                 elfm_detection *out, int *found, elfm_error *err);

/* Refine det again at voxel (x, y, z) of v as elfm_peaks_detect does
 * (position, intensity, sigmas, width; p's fit options), keeping its weak
 * and deep_only flags. v may be a piece of a volume: the fits read row y
 * and column x of plane z (fit_half_xy voxels each way), the voxels along z
 * at (x, y) (fit_half_z) and plane z within +-6 voxels (the width), and
 * take v's edges for the volume's, so a piece must reach the volume's
 * edges where those windows do. The position is in v's um
 * (elfm_volume_x_um). For a peak found in a binned volume, placed again on
 * the full-sampled voxels around it (`eventlfm track --bin-px`). */
void elfm_peaks_refine_at(const elfm_peaks *p, const elfm_volume *v, int x, int y, int z,
                          elfm_detection *det);

/* The threshold the last detect call used (for reports). */
double elfm_peaks_last_threshold(const elfm_peaks *p);

/* Time-surface lag. A surface that weights the object's past positions by
 * exp(-age/tau) is, along the motion, the object's profile (Gaussian,
 * sigma_um) convolved with an exponential trail of length L = speed * tau:
 *   g(x) ~ exp(x/L) erfc((x + sigma^2/L) / (sigma sqrt 2)),
 * x measured forward from the current position. Its maximum lies behind
 * the current position; this returns that distance (>= 0, um). */
double elfm_peaks_trail_lag_um(double trail_um, double sigma_um);

/* Shift a detection forward along its velocity (um/ms) by the lag of a
 * surface with time constant tau_us (the blob width along the motion
 * comes from the detection's sigmas). Zero velocity: unchanged. */
void elfm_detection_correct_lag(elfm_detection *d, double vx_um_per_ms, double vy_um_per_ms,
                                double vz_um_per_ms, double tau_us);

/* The same with a leading-edge term for surfaces of ON events only: a
 * moving object's light rises only on its leading half, so ON events sit
 * ahead of its centre by about its width along the motion (sigma). The
 * shift forward is trail lag - lead_sigmas x sigma (negative: backward).
 * lead_sigmas 0 is elfm_detection_correct_lag. */
void elfm_detection_correct_lag_lead(elfm_detection *d, double vx_um_per_ms,
                                     double vy_um_per_ms, double vz_um_per_ms, double tau_us,
                                     double lead_sigmas);

#ifdef __cplusplus
}
#endif
#endif
