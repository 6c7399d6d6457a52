/* elfm_refocus.h — shift-and-add refocusing of Fourier LFM frames onto the
 * z planes of a calibration, with ghost suppression.
 *
 * FFTW style: plan once, execute many. elfm_refocus_plan_create() turns a
 * calibration into a read-only plan (crop boxes, per-view per-plane integer
 * shifts and bilinear weights, per-voxel view counts); the plan can be shared
 * by any number of threads. Each concurrent execute needs its own workspace
 * (scratch; nothing is allocated per frame once it has reached its size).
 *
 * Geometry (SPEC §2, §3): voxel (X, Y, k) of a W x H x Nz volume samples view v
 * at sensor u = X + cx_v - (W-1)/2 + z_k dx_v (likewise v), bilinearly. A view
 * "samples" a voxel when both bilinear taps lie inside the view's crop box
 * (view_size_px centred on (cx, cy), widened by crop_margin_px, clipped to the
 * sensor); each voxel is the mean over the views that sample it, so views
 * overhanging the sensor do not darken the edges. Voxels no view samples are 0.
 *
 * Two paths, same result (to float rounding; tested to 1e-4 of the maximum):
 *   dense   gathers every voxel plane by plane (cost ~ views x W x H x Nz);
 *   sparse  scatters each listed frame pixel (cost ~ listed pixels x Nz): pixel
 *           u of view v lands on X = u - floor(shift) with weight 1 - frac and
 *           on X - 1 with weight frac, the adjoint of the bilinear gather.
 * AUTO picks sparse when the listed pixels are few (see options).
 *
 * Ghost suppression (applied in execute, after the mean), see docs/recon.md:
 *   threshold: ABS (voxel < value -> 0), FRAC_MAX (< value x volume maximum),
 *              MAD (< median + value x 1.4826 MAD of the non-zero voxels);
 *   agreement: a voxel keeps its value only if at least
 *              ceil(agree_frac x views sampling it) of those views see signal
 *              there (their bilinear sample is non-zero). A ghost is where a
 *              few views' images of different objects happen to overlap; a
 *              real object is seen by (nearly) all views.
 */
#ifndef ELFM_REFOCUS_H
#define ELFM_REFOCUS_H

#include "elfm_calib.h"
#include "elfm_error.h"
#include "elfm_frames.h"
#include "elfm_volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum elfm_refocus_path {
  ELFM_PATH_AUTO = 0,
  ELFM_PATH_DENSE,
  ELFM_PATH_SPARSE
} elfm_refocus_path;

typedef enum elfm_ghost_threshold {
  ELFM_GHOST_THR_NONE = 0,
  ELFM_GHOST_THR_ABS,
  ELFM_GHOST_THR_FRAC_MAX,
  ELFM_GHOST_THR_MAD
} elfm_ghost_threshold;

typedef struct elfm_refocus_options {
  elfm_refocus_path path;
  /* AUTO: sparse when listed pixels < sparse_max_fill x (sum of crop box
   * areas). Default 0.05, from bench_refocus (docs/recon.md). */
  double sparse_max_fill;
  int crop_margin_px;              /* widen each view's crop box (default 0) */
  elfm_ghost_threshold threshold;  /* default NONE */
  double threshold_value;          /* ABS: value; FRAC_MAX: fraction; MAD: k */
  double agree_frac;               /* 0 = off; else in (0, 1]; default 0.3 (docs/recon.md) */
} elfm_refocus_options;

void elfm_refocus_options_default(elfm_refocus_options *o);

typedef struct elfm_refocus_plan elfm_refocus_plan;
typedef struct elfm_refocus_workspace elfm_refocus_workspace;

/* Build a plan for frames of the calibration's sensor and volumes of
 * view_w x view_h x n_planes. On failure *out is NULL and err says why.
 * Free with elfm_refocus_plan_free (NULL is a no-op). */
elfm_status elfm_refocus_plan_create(const elfm_calib *calib, const elfm_refocus_options *opt,
                                     elfm_refocus_plan **out, elfm_error *err);
void elfm_refocus_plan_free(elfm_refocus_plan *p);

/* Plan facts: volume size, sensor size, views that sample voxel (X, Y, k). */
void elfm_refocus_plan_size(const elfm_refocus_plan *p, int *w, int *h, int *nz);
int elfm_refocus_plan_views_at(const elfm_refocus_plan *p, int X, int Y, int k);
const elfm_calib *elfm_refocus_plan_calib(const elfm_refocus_plan *p);

/* View support of voxel (X, Y, k) in `frame`: the number of views whose
 * bilinear sample there (the one the refocus averages) is non-zero; with
 * n_sampling non-NULL, *n_sampling = the views that sample the voxel at
 * all. A bead at the voxel is seen by most of the views, a ghost (images
 * of other objects that happen to line up there) by a few: a test for a
 * detected peak, where the agreement rule is a test for every voxel.
 * 0 outside the volume. O(views). */
int elfm_refocus_view_support(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y,
                              int k, int *n_sampling);

/* The share of the views' crop-box pixels that are non-zero in `frame`
 * (0..1; a pixel in two boxes counts in each): how crowded the views are.
 * A ghost is a voxel where the sample points of enough views land on
 * other objects' images by chance, and that chance grows with this share
 * (on a time surface, the pixels that fired in the window). 0 for a plan
 * without boxes and for a frame of another size than the plan's sensor.
 * O(frame's listed pixels): the plan counts each pixel's boxes. */
double elfm_refocus_occupancy(const elfm_refocus_plan *p, const elfm_frame *frame);

/* The view support of voxel (X, Y, k) as above, leaving out the views whose
 * signal another object's image explains: where the voxel's sample point
 * lies within r_px of the image of one of `others` in that view (n_others
 * voxel positions X, Y, k, fractional allowed). *n_explained (may be NULL)
 * = the views with signal left out. Why: a refocusing ghost is a voxel at
 * which one bright object's images in several views line up, at another
 * depth; its views with signal are that object's images, and with that
 * object among `others` they no longer count. Another object beside it
 * has images of its own, which stay. O(views x n_others). */
int elfm_refocus_view_support_unexplained(const elfm_refocus_plan *p, const elfm_frame *frame,
                                          int X, int Y, int k, const double (*others)[3],
                                          int n_others, double r_px, int *n_sampling,
                                          int *n_explained);

/* The refocused value of voxel (X, Y, k) from `frame`, as
 * elfm_refocus_execute would write it there without ghost suppression (the
 * mean of the sampling views' bilinear samples); 0 outside the volume.
 * O(views): for a point found in a frame whose volume is gone. */
double elfm_refocus_value_at(const elfm_refocus_plan *p, const elfm_frame *frame, int X, int Y,
                             int k);

/* Voxels X0 .. X0+w-1, Y0 .. Y0+h-1 of plane k, each as
 * elfm_refocus_value_at gives it (the same values; 0 outside the volume),
 * into out (w x h doubles, row by row). O(views x w x h) with a view's
 * setup once per piece, not per voxel: the full-sampled voxels around a
 * peak found in a binned volume (`eventlfm track --bin-px`). */
void elfm_refocus_plane_piece(const elfm_refocus_plan *p, const elfm_frame *frame, int X0, int Y0,
                              int w, int h, int k, double *out);

/* Give vol the frame's times (t_us, frame, window, events) and the plan's
 * geometry, as elfm_refocus_execute does, leaving its voxels as they are
 * (for a run that reads frames without refocusing them). */
void elfm_refocus_stamp(const elfm_refocus_plan *p, const elfm_frame *frame, elfm_volume *vol);

/* The refocused value at sub-voxel position (X, Y, k) (voxel units, e.g.
 * from elfm_volume_x_vox), trilinear between the 8 voxels around it, each
 * as elfm_refocus_value_at gives it (0 outside the volume). O(8 views):
 * an object's intensity in a frame without refocusing the frame. */
double elfm_refocus_sample(const elfm_refocus_plan *p, const elfm_frame *frame, double X, double Y,
                           double k);

/* Localise a point from its images in the views of `frame` (the Fourier
 * LFM triangulation; recon/localize.c): starting at volume position
 * (x_vox, y_vox, z_vox) (voxel units, fractional), measure each view's
 * image centre as the centroid of a (2 half_window_px + 1)^2 window
 * (pixel weights value^power), re-centre, and fit (X, Y, z) to all of them
 * by weighted least squares; views that miss the fit by more than
 * outlier_px are dropped and the others weighted robustly. Returns 1 with
 * *out filled, 0 when fewer than min_views views agree with the fit, the
 * fit leaves the volume or the input is not usable (the caller keeps its
 * own estimate). Read-only on plan and frame: any thread. */
typedef struct elfm_localize_options {
  int half_window_px;  /* window half-size (2: 5 x 5 px) */
  int iterations;      /* plain re-centring passes before the robust ones (4; below 1
                          counts as 1, above 100 is refused: the count plus the robust
                          passes must not overflow an int) */
  double outlier_px;   /* drop a view whose centroid misses the fit by more (1.5) */
  int min_views;       /* fewer views agreeing: no result (6) */
  int power;           /* pixel weight value^power: on a time surface the newest
                          events count most (3) */
  double deep_z_um;    /* on a deep window's frames (elfm_frame.recent_floor > 0): a fit
                          started at |z| >= this reads the older pixels too, a nearer
                          one the window's alone; INFINITY (default): always the
                          window's, as the refocus reads them */
} elfm_localize_options;

typedef struct elfm_localize_result {
  double x_vox, y_vox, z_vox; /* position, voxel units of the plan's volume */
  int n_views;                /* views that agree with the fit (robust weight >= 1/2) */
  int n_views_first;          /* of those, views whose window in the first (wanted) frame
                                 alone agrees too (= n_views for one frame) */
  double rms_px;              /* their weighted RMS miss, px */
  double sd_px;               /* rms_px / sqrt(n_views): the fit's scatter, px */
} elfm_localize_result;

void elfm_localize_options_default(elfm_localize_options *o);
int elfm_refocus_localize(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                          double y_vox, double z_vox, const elfm_localize_options *o,
                          elfm_localize_result *out);
/* The same over n_frames (1..64) frames of one moving object: frames[0] is
 * the frame the position is wanted for, off_vox[j] where the object was in
 * frames[j] relative to frames[0] (X, Y in voxels, z in um; NULL = all
 * zero). Each view's centroid sums the frames' windows, each placed where
 * the object was and moved back by that image shift: a dim object's events
 * from several windows add up at its position in frames[0]. */
int elfm_refocus_localize_frames(const elfm_refocus_plan *p, const elfm_frame *const *frames,
                                 const double (*off_vox)[3], int n_frames, double x_vox,
                                 double y_vox, double z_vox, const elfm_localize_options *o,
                                 elfm_localize_result *out);

/* The single-frame fit of a point with other objects nearby: near_vox[0 ..
 * n_near) are their positions (voxel units, as x_vox ...). In each view, a
 * neighbour whose image lies within a few windows of the point's takes its
 * light out of the point's window before the centroid: an image is taken
 * to be symmetric about its centre, so the neighbour's light at pixel x is
 * read at x mirrored through the neighbour's centre, on its far side, and
 * subtracted (recon/localize.c). Two C. elegans neurons 6 um apart, whose
 * blurred images overlap, pull each other's centroids otherwise. */
int elfm_refocus_localize_near(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                               double y_vox, double z_vox, const double (*near_vox)[3], int n_near,
                               const elfm_localize_options *o, elfm_localize_result *out);

/* elfm_refocus_localize that also says, per view v of the plan's
 * calibration (elfm_refocus_plan_calib(p)->n_views entries), where its
 * image centre lay off the fitted point's projection: miss_px[2 v] in u,
 * miss_px[2 v + 1] in w (px, image minus projection), and weight[v] its
 * weight in the fit: > 0 for every view the fit kept, also those its
 * robust weighting played down (not counted in n_views); 0, with misses
 * 0, for a view dropped as an outlier (beyond outlier_px) or without signal.
 * For fitting the views' centres to a recording (elfm_calib_refine); the
 * arrays are left unspecified when it returns 0. */
int elfm_refocus_localize_misses(const elfm_refocus_plan *p, const elfm_frame *frame, double x_vox,
                                 double y_vox, double z_vox, const elfm_localize_options *o,
                                 elfm_localize_result *out, double *miss_px, double *weight);

/* Per-execution scratch for `p`. Free with elfm_refocus_workspace_free.
 * The workspace remembers which rows of the volume it last wrote on the
 * sparse path, so it clears only those next time: between two executes
 * with the same volume and workspace, only zero voxels (a threshold) may be
 * changed by the caller; after any other change, call
 * elfm_refocus_workspace_forget(). */
elfm_status elfm_refocus_workspace_create(const elfm_refocus_plan *p,
                                          elfm_refocus_workspace **out, elfm_error *err);
void elfm_refocus_workspace_free(elfm_refocus_workspace *ws);
void elfm_refocus_workspace_forget(elfm_refocus_workspace *ws);
/* The path the last execute took (DENSE or SPARSE). */
elfm_refocus_path elfm_refocus_workspace_last_path(const elfm_refocus_workspace *ws);

/* Refocus `frame` (the full sensor) into `vol` (created with the plan's
 * size; its t_us/frame/axes are set from the frame and the calibration),
 * applying the plan's ghost suppression. The plan's path choice is used. */
elfm_status elfm_refocus_execute(const elfm_refocus_plan *p, const elfm_frame *frame,
                                 elfm_volume *vol, elfm_refocus_workspace *ws, elfm_error *err);
/* Same with an explicit path (DENSE or SPARSE; AUTO = the plan's rule). */
elfm_status elfm_refocus_execute_path(const elfm_refocus_plan *p, elfm_refocus_path path,
                                      const elfm_frame *frame, elfm_volume *vol,
                                      elfm_refocus_workspace *ws, elfm_error *err);

/* ELFM_OK when the plan was made for a calibration of this sensor, view
 * size, views and planes; otherwise ELFM_ERR_INVALID with both described
 * (a plan lent to a run: elfm_recon_options.plan). */
elfm_status elfm_refocus_plan_fits(const elfm_refocus_plan *p, const elfm_calib *c,
                                   elfm_error *err);

/* A volume of the plan's size (zeroed), for refilling frame after frame:
 * on 2 MiB pages where the system has them, which is slow to make and free
 * one after another (elfm_volume_create is for those). Free with
 * elfm_volume_free. */
elfm_volume *elfm_refocus_volume_create(const elfm_refocus_plan *p, elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
