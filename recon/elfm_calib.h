/* elfm_calib.h — Fourier LFM calibration: where a point of object space
 * lands in each view (SPEC §2) and the calib.json file (SPEC §3).
 *
 *   u = cx + x_um / um_per_px + z_um * dx_px_per_um
 *   v = cy + y_um / um_per_px + z_um * dy_px_per_um
 *
 * `views` is authoritative; `optics` is informational (has_optics says
 * whether it was filled). Plain value type: no allocation, copy freely.
 */
#ifndef ELFM_CALIB_H
#define ELFM_CALIB_H

#include <stdint.h>

#include "elfm_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* 9 x 9 lenslets is more than any Fourier LFM we know of uses (5 x 5 here). */
#define ELFM_MAX_VIEWS 81

typedef struct elfm_view {
  int i, j;                 /* column / row offset in lenslets; (0,0) centre */
  double cx_px, cy_px;      /* sensor position of the on-axis focal point */
  double dx_px_per_um, dy_px_per_um; /* image shift per micrometre of depth */
} elfm_view;

typedef struct elfm_optics {
  double na, n_medium, magnification, f_tube_mm, f_fourier_mm, f_mla_mm,
      mla_pitch_um, relay, wavelength_um;
  int lenslets_per_side;    /* 5 for the 5 x 5 array */
  /* The lens array turned about the optical axis against the sensor's rows,
   * degrees (0: aligned). It turns both where each lenslet's view lands and
   * the direction its images move with depth (a lenslet's view moves along
   * its offset in the pupil); the images themselves do not turn. Sensor
   * pixel axes, x along a row, y down a column: an offset (x, y) becomes
   * (x cos a - y sin a, x sin a + y cos a). */
  double mla_rotation_deg;
} elfm_optics;

typedef struct elfm_calib {
  int sensor_width_px, sensor_height_px;
  double pixel_um;
  int has_optics;
  elfm_optics optics;
  double um_per_px;
  int view_w_px, view_h_px; /* size of each cropped view = volume W x H */
  int n_views;
  elfm_view views[ELFM_MAX_VIEWS];
  double z_min_um, z_max_um, z_step_um;
} elfm_calib;

/* The paper's system (SPEC §2): EVK4 behind 20x/0.75 NA, f_fourier 80 mm, ... */
void elfm_optics_default(elfm_optics *o);

/* Build a calibration from optics for a sensor (SPEC §2 formulas, exact
 * non-paraxial view angles; views outside the pupil are left out). Views
 * are laid out on the sensor around its centre at the nominal spacing.
 * view size and z range: view_w/h_px = 144, z = -100..100 step 2 unless the
 * caller changes them afterwards. */
elfm_status elfm_calib_from_optics(const elfm_optics *o, int sensor_width_px,
                                   int sensor_height_px, double pixel_um,
                                   elfm_calib *out, elfm_error *err);

/* Read / write calib.json. Load checks every field (finite, in range) and
 * names the file and the offending key on error. */
elfm_status elfm_calib_load(const char *path, elfm_calib *out, elfm_error *err);
elfm_status elfm_calib_save(const elfm_calib *c, const char *path, elfm_error *err);

/* Same checks as elfm_calib_load on JSON text already in memory (len bytes,
 * need not be NUL-terminated); `path` only names the source in messages. */
elfm_status elfm_calib_parse(const char *text, size_t len, const char *path,
                             elfm_calib *out, elfm_error *err);

/* Sensor position of object point (x,y,z) in view `v` (0 <= v < n_views). */
void elfm_calib_project(const elfm_calib *c, int v, double x_um, double y_um,
                        double z_um, double *u_px, double *v_px);

/* The share (0..1) of view v's crop (view_w x view_h px about its centre)
 * that lies on the sensor; 0 for a v out of range. A grid wider than the
 * sensor (the paper's 5 x 5 overhangs the EVK4's 720 rows by 14-15 %)
 * leaves objects far from the axis seen by fewer views. */
double elfm_calib_view_on_sensor(const elfm_calib *c, int v);

/* Number of z planes: floor((z_max - z_min) / z_step + 0.5) + 1. */
int elfm_calib_n_planes(const elfm_calib *c);

/* Refocus on other z planes than the calibration's: z_min_um .. z_max_um
 * every z_step_um (NaN keeps the calibration's value). The same checks as
 * elfm_calib_load (|z| <= 10000 um, max >= min, step 0.001..10000 um, at
 * most 4096 planes); on error *c is unchanged (ELFM_ERR_RANGE). The views
 * are not touched: their shift per um holds for any plane. */
elfm_status elfm_calib_set_planes(elfm_calib *c, double z_min_um, double z_max_um, double z_step_um,
                                  elfm_error *err);

/* The calibration of the sensor binned factor x factor (elfm_frame_bin):
 * sensor ceil(w / factor) x ceil(h / factor), pixel_um and um_per_px
 * factor times, each view's shift per um over factor, its centre where the
 * block of its pixel lies (a block's centre is at full-pixel (factor - 1) /
 * 2 from its first pixel's), the view size over factor (rounded down). The
 * planes and the optics stay. A voxel of the binned volume and one of the
 * full-sampled volume at the same (x, y, z) um see the same sensor point,
 * both volumes centred on the views' centres (elfm_volume_x_um). Factor 1
 * copies; ELFM_ERR_INVALID for a factor below 1 or a binned view smaller
 * than 3 x 3 px. */
elfm_status elfm_calib_bin(const elfm_calib *c, int factor, elfm_calib *out, elfm_error *err);

/* ---- the views' centres fitted to a recording (calib_refine.c) ----
 * Collect, for many points fitted from all views, each view's miss
 * (elfm_refocus_localize_misses), then move every view's centre by the
 * median of its misses, cleared of the two moves no recording can see (all
 * views alike: the volume's x-y origin; in proportion to the disparities:
 * its focal plane). Repeat with the moved centres until the moves are
 * small. `eventlfm calib refine` is the command; docs/recon.md "Fitting
 * the views' centres" has the measurements.
 *
 *   elfm_calib_refine *r;  elfm_calib_refine_create(cal.n_views, 20000, &r, &err);
 *   for each point: elfm_calib_refine_add(r, at_px, miss_px, weight);
 *   elfm_calib_refine_apply(r, 20, &cal, shift_px, &n_moved, &err);  (and again) */
typedef struct elfm_calib_refine elfm_calib_refine;
/* A collector for up to max_points points (1..10^7) of n_views views
 * (1..ELFM_MAX_VIEWS); 8 bytes per point and view. */
elfm_status elfm_calib_refine_create(int n_views, size_t max_points, elfm_calib_refine **out,
                                     elfm_error *err);
void elfm_calib_refine_free(elfm_calib_refine *r);
/* The gauge taken out of per-view moves s (one axis, nv views): s[v] -= a
 * + b d[v] over the views with use[v], least squares, d the views'
 * disparity on that axis; with fewer than 3 such views or no spread of d,
 * the mean only. */
void elfm_calib_gauge_clear(int nv, const int *use, const double *d, double *s);
/* One point's misses (2 per view, px) and weights (0: the view did not
 * agree, skipped), and where its image lay in each view (at_px: sensor u,
 * w, 2 per view; may be NULL). 1, or 0 when max_points are already held
 * (ignored). */
int elfm_calib_refine_add(elfm_calib_refine *r, const double *at_px, const double *miss_px,
                          const double *weight);
size_t elfm_calib_refine_points(const elfm_calib_refine *r);
/* Move each view of c with at least min_points misses by their median
 * (gauge cleared as above; the others stay); shift_px (2 per view, may be
 * NULL) gets the moves, *n_moved (may be NULL) the views moved. Empties the
 * collector for the next pass. ELFM_ERR_INVALID when c has another number
 * of views. */
elfm_status elfm_calib_refine_apply(elfm_calib_refine *r, int min_points, elfm_calib *c,
                                    double *shift_px, int *n_moved, elfm_error *err);
/* A view whose images (at_px of the points it agreed with; the points'
 * projections in the coarse step) all lay within 2 px RMS of one place
 * does not move by its own misses: their median rests on one pixel phase
 * and on whatever that place holds (the central view of one bead swept
 * through z). When 6 or more other views moved, it goes where the grid of
 * their centres puts it (cx, cy affine in the lenslets' (i, j)). still
 * says whether the last apply (or apply_votes) placed view v so, and puts
 * its images' RMS distance from their mean in *spread_px (may be NULL;
 * NaN when none were given). */
int elfm_calib_refine_still(const elfm_calib_refine *r, int v, double *spread_px);
/* ... the 2 px of that rule (track's check of the views leaves such views
 * unjudged too) */
#define ELFM_CALIB_STILL_PX 2.0
/* The coarse step, for centres too far off for the view fit's window (a
 * calibration from the optics alone): every point votes, in each view,
 * with the frame's values at offsets up to radius_px from its projection;
 * each view moves to the peak of its votes (gauge cleared as above; a view
 * whose peak is not twice the votes' median stays). Fewer than
 * ELFM_CALIB_VOTES_MIN points make no map, and no view moves: one point's
 * frame (a bead swept through z, its first 200 ms on the time surface)
 * moved views by up to 15 px. set_search allocates the votes (0..64 px; 0
 * frees them), apply_votes empties them. */
#define ELFM_CALIB_VOTES_MIN 20
struct elfm_frame;
elfm_status elfm_calib_refine_set_search(elfm_calib_refine *r, int radius_px, elfm_error *err);
void elfm_calib_refine_vote(elfm_calib_refine *r, const elfm_calib *c, const struct elfm_frame *f,
                            double x_um, double y_um, double z_um);
size_t elfm_calib_refine_votes(const elfm_calib_refine *r);
elfm_status elfm_calib_refine_apply_votes(elfm_calib_refine *r, elfm_calib *c, double *shift_px,
                                          int *n_moved, elfm_error *err);

/* ---- the views' centres from objects swept through z (calib_sweep.c) ----
 * For centres too far off for the coarse step's refocused peaks (a
 * calibration from the optics alone) on a recording of one bright object
 * moved along the axis (a bead on a piezo), or of several side by side
 * moved together (beads on a slide): each view is looked at on its own.
 * spots finds, in each view's crop about the centres given to create, the
 * frame's brightest 3 x 3 spot of positive values (its sum less its
 * brightest pixel, strength: a hot pixel alone is no spot) and its 5 x 5
 * centroid (at_px, 2 per view, NaN where the crop is empty), how far it
 * stands out: its strength over the next spot's 5 px or more away
 * (contrast, infinite with no other); and the view's spots down to 0.3 of
 * the brightest, none within 4 px of a brighter one, the brightest
 * ELFM_CALIB_SWEEP_MAX_SPOTS (n_spots, spot_px); ELFM_ERR_NOMEM when it
 * found no memory for its list. add keeps a frame's spots, the brightest
 * where its contrast is ELFM_CALIB_SWEEP_CONTRAST or more (0 when
 * max_frames are held, ~6.7 KB each on 25 views; t_us: the frame's time).
 * apply fits image = centre + the object's place + disparity x its depth
 * in each frame (the disparities kept), moves every view with min_images
 * images near that model to its fitted centre (cleared of the gauge, as
 * refine_apply; *n_moved says how many), sets the others, and those that
 * do not tell the depth (the central view), on the grid of those when 6 or
 * more moved, and empties the collector. When the views' median share of
 * brightest spots near the model is under 0.5 (not one object), the spots
 * are matched to one pattern of objects each at its own place and depth,
 * moved in each frame by the view's translation, and the translations
 * fitted instead (recon/calib_sweep_pattern.c); when under half of the
 * frames match it (objects that move each their own way), or its fit too
 * is under 0.5, nothing moves; nor when no pattern is matched and the
 * views' median share of frames with two spots or more is
 * ELFM_CALIB_SWEEP_SEVERAL or more (several objects: one object's
 * brightest spots are fitted only where there is one), nor when a fitted
 * view lies more than ELFM_CALIB_SWEEP_OFF_GRID_PX from the lenslets'
 * grid (cx, cy affine in (i, j)) of the fitted views (objects taken for
 * each other). result gives the last apply's fit
 * (elfm_calib_sweep_fit), with how fast the object moved in z by the
 * disparities as they are (a piezo's known speed gives their scale, which
 * no recording of unknown motion can: docs/recon.md "What it still cannot
 * see") and the depth where its images were strongest, the focus (which
 * elfm_calib_move_focus makes z = 0; the grid then gives the relay's
 * magnification: elfm_calib_grid_pitch). spots is safe on many threads at once (it reads the collector's
 * map of views only). docs/recon.md "A sweep's views, frame by frame",
 * "Several beads swept together". */
#define ELFM_CALIB_SWEEP_CONTRAST 2.0
#define ELFM_CALIB_SWEEP_SEVERAL 0.5
#define ELFM_CALIB_SWEEP_OFF_GRID_PX 3.0
typedef struct elfm_calib_sweep elfm_calib_sweep;
elfm_status elfm_calib_sweep_create(const elfm_calib *c, size_t max_frames, elfm_calib_sweep **out,
                                    elfm_error *err);
void elfm_calib_sweep_free(elfm_calib_sweep *s);
#define ELFM_CALIB_SWEEP_MAX_SPOTS 32
typedef struct elfm_calib_sweep_image {
  double at_px[2 * ELFM_MAX_VIEWS];  /* each view's brightest spot, NaN: none */
  double strength[ELFM_MAX_VIEWS];   /* its 3 x 3 sum less its brightest pixel */
  double contrast[ELFM_MAX_VIEWS];   /* its strength over its rival's */
  int n_spots[ELFM_MAX_VIEWS];       /* each view's spots, brightest first: */
  float spot_px[ELFM_MAX_VIEWS][ELFM_CALIB_SWEEP_MAX_SPOTS][2];
} elfm_calib_sweep_image;
elfm_status elfm_calib_sweep_spots(const elfm_calib_sweep *s, const struct elfm_frame *f,
                                   elfm_calib_sweep_image *img, elfm_error *err);
int elfm_calib_sweep_add(elfm_calib_sweep *s, int64_t t_us, const elfm_calib_sweep_image *img);
size_t elfm_calib_sweep_frames(const elfm_calib_sweep *s);
elfm_status elfm_calib_sweep_apply(elfm_calib_sweep *s, int min_images, elfm_calib *c, double *shift_px,
                                   int *n_moved, elfm_error *err);
typedef struct elfm_calib_sweep_fit {
  int frames_used;              /* frames that told the depth */
  int images[ELFM_MAX_VIEWS];   /* per view, its images near the model */
  int placed[ELFM_MAX_VIEWS];   /* per view, set on the grid of the others */
  double rms_px;                /* the images' RMS distance from the model */
  double agree;                 /* the views' median share of spots near the model */
  int objects;                  /* 1 (the brightest spots), or the pattern's objects */
  double pattern_share;         /* several: the views' median share of frames placed, */
  double depth_um;              /* and how far apart in depth they lie */
  double several_share;         /* the views' median share of frames with 2+ spots */
  double off_grid_px;           /* the fitted views' largest distance from their grid */
  int off_grid_view;            /* ... that view (-1: they span no grid) */
  /* |dz/dt| over 40 ms spans within the middle half of the fitted depths:
   * median and middle half; NaN with fewer than 20 spans */
  double speed_um_per_ms, speed_lo_um_per_ms, speed_hi_um_per_ms;
  /* the depth, in the calibration apply leaves, where the views' images
   * are strongest (the object in focus: docs/recon.md "The focal plane
   * from a sweep"); NaN when the sweep did not go through it and out.
   * With frames going up and frames going down that each show it (a
   * sweep both ways), the mean of the two (focus_up_um, focus_down_um,
   * else NaN) */
  double focus_um, focus_up_um, focus_down_um;
} elfm_calib_sweep_fit;
void elfm_calib_sweep_result(const elfm_calib_sweep *s, elfm_calib_sweep_fit *fit);

/* The plane at depth z_um made the focal plane (z = 0): every view's
 * centre moved by its disparity x z_um, so that image = centre + x + d z
 * keeps every object's images (each at z - z_um now). A sweep's focus
 * (elfm_calib_sweep_fit.focus_um) is such a plane. Not finite: nothing. */
void elfm_calib_move_focus(elfm_calib *c, double z_um);

/* The lenslets' grid on the sensor: the mean length of its two lattice
 * vectors (cx, cy affine in (i, j) over every view, least squares), px;
 * NaN when the views do not span it. The lenslets' pitch is made to well
 * under 0.1 % and the pixels' too, so between two calibrations of one
 * microscope it changes with the relay's magnification alone (the optics
 * between the lens array and the sensor), which scales everything on the
 * sensor: scale_relay(c, k) takes the relay's magnification k times c's
 * (um_per_px / k, every disparity x k, optics.relay x k; the centres
 * stay). Not finite or not above 0: nothing. */
double elfm_calib_grid_pitch(const elfm_calib *c);
void elfm_calib_scale_relay(elfm_calib *c, double k);

/* The lens array turned about the optical axis (elfm_optics.mla_rotation_deg):
 * turn turns every view's centre about the centres' mean and its disparity
 * (dx, dy) by angle_deg (sensor pixel axes, as in elfm_optics);
 * turn_disparities turns the disparities alone. Both add the angle to
 * optics.mla_rotation_deg when c has optics. turns gives how far c's
 * centres (about their mean) and its disparities are turned against the
 * lenslets' lattice (i, j) (least squares, degrees; 0 where nothing tells,
 * as for one view). `calib refine` searches the turn first and at the end
 * turns the disparities by the difference. */
void elfm_calib_turn(elfm_calib *c, double angle_deg);
void elfm_calib_turn_disparities(elfm_calib *c, double angle_deg);
void elfm_calib_turns(const elfm_calib *c, double *centres_deg, double *disparities_deg);

#ifdef __cplusplus
}
#endif
#endif
