/* link_internal.h — private to tracker/: the linker's state and the helpers
 * shared by link.c (life cycle and the per-frame linking, steps 1-4 of
 * elfm_link_step, see elfm_link.h), link_candidates.c (its step 2) and
 * link_repair.c (the repair steps 5 to 7 that step runs last: stitching,
 * swap and encounter review). Not public: callers use elfm_link.h. */
#ifndef ELFM_LINK_INTERNAL_H
#define ELFM_LINK_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_link.h"
#include "elfm_score.h"

/* A track still being extended, with its fits and this frame's prediction. */
typedef struct live_track {
  elfm_track *t;
  int64_t last_frame, last_t_us;
  double last[3];           /* last real position */
  double vel_um_per_ms[3];  /* long constant-velocity fit; the prior with one point */
  double lin_pos[3];        /* that fit's position at the last point's time */
  double fit_pos[3], fit_vel[3], fit_acc[3]; /* short fit, at the last point's time */
  int has_short;            /* the short fit exists (>= 4 points) */
  elfm_link_circle circ;    /* circle fit over circle_points points (circ.ok: it exists) */
  elfm_link_circle circ_next; /* circle over circle_next_path_um of path (circ_next.ok) */
  double pred[3];           /* prediction for the current frame */
  /* The current frame's two predictions when the track was seen in the
   * last frame and circ_next exists (pred_circ_ok), made for pred_t_us:
   * the short fit's and circ_next's; the mean squared miss of each on the
   * track's own points (decaying), over n_scored points
   * (elfm_link_options.circle_next_path_um). */
  double pred_short[3], pred_circ[3];
  int pred_circ_ok;
  int64_t pred_t_us;
  double miss2_short, miss2_circ;
  int n_scored;
  double gate_um;           /* gate for the current frame */
  /* In a recording at rest, a track dark for more than short_gap frames
   * may also have stayed where it was (moving with the prior velocity):
   * detections within rest_gate_um of rest[] are its candidates too
   * (predict_rest in link.c) */
  int has_rest;
  double rest[3], rest_gate_um;
  int missed;               /* frames missed before the current frame */
  size_t tail0;             /* index of the point that closed the last gap (0 none) */
  int review;               /* that gap closing is still to be reviewed (step 6) */
} live_track;

/* One candidate detection of a track and the cost of joining it. */
typedef struct link_cand {
  int det;
  double cost;
} link_cand;

/* Two tracks that met (step 7): the frames they were within
 * encounter_um, still to be reviewed. */
typedef struct link_encounter {
  int64_t a_id, b_id;
  int64_t first, last;
} link_encounter;

/* A track's x for step 7's sweep over the tracks sorted by it. */
typedef struct link_xkey {
  double x_um;
  int track;
} link_xkey;

#define LINK_DET_VEL 9
/* elfm_link_last_miss_um: the points a track needs before its prediction
 * is judged (its short fit, >= 4 points, and one more) */
#define LINK_MISS_MIN_POINTS 5

/* The linker (opaque in elfm_link.h). */
struct elfm_linker {
  elfm_link_options o;
  live_track *live;
  size_t n_live, cap_live;
  elfm_track **fin;          /* FIFO of finished tracks: fin[fin_head .. fin_head+fin_n) */
  size_t fin_head, fin_n, fin_cap;
  link_encounter *enc;       /* step 7's pending encounters, in the order they began */
  size_t n_enc, cap_enc;
  int64_t next_id, last_frame, last_t_us;
  int64_t n_twins;           /* tracks step 8 joined to a younger twin */
  int64_t n_late_stitches;   /* tracks step 5b continued as a young one */
  int started;
  /* per-frame scratch, grown on demand */
  size_t cap_det, cap_trk;
  float *pts;                /* n_det x 3, z scaled by 1/kz */
  int *nn_idx;               /* max_candidates */
  float *nn_dist;
  link_cand *cand;           /* n_trk x max_candidates */
  int *n_cand;               /* per track */
  int *uf;                   /* union-find over tracks then detections */
  int *comp_of, *comp_start, *comp_fill, *members; /* grouping */
  int *track_det, *det_track, *det_local;
  int64_t *det_id;
  double *det_vel;           /* n_det x LINK_DET_VEL: the joined track's velocity now
                              * and its long fit's (um/ms; NaN for none or one
                              * point), its number of points, the time its
                              * long fit spans (ms), and how far the detection
                              * lay from the track's prediction (um, z / kz;
                              * NaN unless elfm_link_last_miss_um's terms hold) */
  size_t cap_cost;
  double *cost;
  int *row_to_col;
  int *rows, *cols;
  link_xkey *xkeys;          /* n_trk: step 7's sweep */
  /* straight_gaps: the objects' common velocity this frame (um/ms), from
   * elfm_link_common_velocity; has_common_vel 0 when it could not be told */
  double common_vel[3];
  int has_common_vel;
  double *vel_scratch;       /* its medians' scratch, cap_vel_scratch values */
  size_t cap_vel_scratch;
  elfm_assign_workspace *aws;
};

/* The track's velocity now (um/ms): the short fit's at its last point, else
 * the long one. */
static inline const double *elfm_link_current_velocity(const live_track *lt)
{
  return lt->has_short ? lt->fit_vel : lt->vel_um_per_ms;
}

/* link.c: scratch. Both only grow, keep their contents, and on
 * ELFM_ERR_NOMEM (err filled) leave every array valid and owned by l. */

/* Make the per-frame scratch (candidates, grouping, rows/cols, det_*) hold
 * n_trk tracks and n_det detections. */
elfm_status elfm_link_reserve(elfm_linker *l, size_t n_trk, size_t n_det, elfm_error *err);

/* The cost matrix l->cost holds at least `need` entries (nr x nc of one
 * assignment). */
elfm_status elfm_link_reserve_cost(elfm_linker *l, size_t need, elfm_error *err);

/* link_fit.c: fits (prediction: link_predict.c; the turn: link_circle.c). */

/* Mean intensity of t's points a .. b-1 (0 when the range is empty). */
double elfm_link_mean_intensity(const elfm_track *t, size_t a, size_t b);

/* The determinant of a 3x3 matrix, and x = m^-1 b by Cramer's rule given
 * that determinant (non-zero; each caller judges when it is too small):
 * the 3x3 normal equations of elfm_link_fit_quad and of the circle fit. */
static inline double link_det3(const double m[3][3])
{
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

static inline void link_cramer3(const double m[3][3], double det, const double b[3], double x[3])
{
  for (int j = 0; j < 3; j++) { /* replace column j by b */
    double a[3][3];
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) a[r][c] = c == j ? b[r] : m[r][c];
    x[j] = link_det3(a) / det;
  }
}

/* Least-squares p = c0 + c1 t + c2 t^2 over pts[k0 .. k1) (t in ms from
 * tr): position, velocity and acceleration at tr. 0 when fewer than 3
 * distinct times (outputs untouched). */
int elfm_link_fit_quad(const elfm_detection *pts, size_t k0, size_t k1, int64_t tr,
                       double pos[3], double vel[3], double acc[3]);

/* Least-squares p = c0 + c1 t over pts[k0 .. k1) (t in ms from tr):
 * position and velocity at tr. 0 when fewer than 2 distinct times
 * (outputs untouched). */
int elfm_link_fit_line(const elfm_detection *pts, size_t k0, size_t k1, int64_t tr, double pos[3],
                       double vel[3]);

/* Least-squares fits over the recent real points of lt->t (at least one),
 * times relative to the last point in ms (never float absolute times): a
 * constant velocity over o->history points into lt->vel_um_per_ms
 * (o->prior_velocity_um_per_ms when fewer than 2 distinct times) and a
 * constant acceleration over o->short_history points, fewer when
 * o->short_path_um > 0 and they span more path than that (at least 4),
 * into lt->fit_pos/fit_vel/fit_acc (lt->has_short says whether it exists:
 * >= 4 points, 3 distinct times). */
void elfm_link_fit_velocity(live_track *lt, const elfm_link_options *o);

/* Position after dt_ms of a constant-rate turn (the coordinated-turn
 * model): the velocity v keeps its length and rotates at omega = v x a /
 * |v|^2, the part of the acceleration normal to it; the tangential part is
 * dropped. Why: beyond a few frames an extrapolated acceleration diverges
 * and a straight line leaves a helix (flow beads turn ~17 degrees per ms),
 * while the turn stays on the circle of radius |v| / |omega|:
 *   p(t) = p0 + v sin(w t) / w + (k x v)(1 - cos(w t)) / w,  k = omega / w. */
void elfm_link_predict_turn(const double p0[3], const double v[3], const double acc[3],
                            double dt_ms, double out[3]);

/* link_circle.c: the circle fit. Over pts[k0 .. k1) (>= 6 points; times
 * in ms from tr): the plane of least spread through their mean, the
 * algebraic circle in it, and the angle along it (each step unwrapped as
 * the turn nearest the rate of the points before it) as a straight line in
 * time. 0 (c->ok 0) when the circle is wider than o->circle_max_radius_um
 * (a path that does not turn), the points cover less than
 * o->circle_min_arc_rad of it, or it does not fit them
 * o->circle_line_ratio times better than a straight line at constant
 * velocity (root mean square, z / o->kz). */
int elfm_link_fit_circle(const elfm_link_options *o, const elfm_detection *pts, size_t k0,
                         size_t k1, int64_t tr, elfm_link_circle *c);

/* Position on the circle dt_ms after its reference time. */
void elfm_link_circle_predict(const elfm_link_circle *c, double dt_ms, double out[3]);
/* Score the two predictions made for d's frame against d (link_predict.c). */
void elfm_link_score_predictions(const elfm_link_options *o, live_track *lt, const elfm_detection *d);
/* How far d lies from the prediction pred, in the linker's metric (z / kz). */
double elfm_link_miss_um(const elfm_link_options *o, const double pred[3], const elfm_detection *d);

/* Can detection d join a track, dark for `missed` frames, whose hypothesis
 * puts it at c[] within gate_um? 1 with *cost = d2 / gate^2 + gap_cost x
 * missed (d2 the squared anisotropic distance, z / kz), the cost every
 * candidate of steps 2 and 3b carries; 0 outside the gate, and for a weak
 * detection beyond the weak gate. */
static inline int link_gated_cost(const elfm_link_options *o, const double c[3], double gate_um,
                                  int missed, const elfm_detection *d, double *cost)
{
  const double g2 = gate_um * gate_um;
  const double dx = d->x_um - c[0], dy = d->y_um - c[1], dz = (d->z_um - c[2]) / o->kz;
  const double d2 = dx * dx + dy * dy + dz * dz;
  if (d2 >= g2) return 0;
  if (d->weak && o->weak_gate_um > 0 && d2 >= o->weak_gate_um * o->weak_gate_um) return 0;
  *cost = d2 / g2 + o->gap_cost * missed;
  return 1;
}

/* link_candidates.c: step 2 of elfm_link_step. For each of the nt live
 * tracks (their pred, gate_um, missed and rest hypothesis set by step 1),
 * the detections within its gate, nearest first, at most max_candidates:
 * l->cand[i * max_candidates ..] and l->n_cand[i], each at the cost d2 /
 * gate2 + gap_cost x missed, a detection found under both hypotheses at
 * its lower cost. From a FLANN k-d tree over the frame's nd detections, or
 * every pair with o.brute_force. */
elfm_status elfm_link_candidates(elfm_linker *l, const elfm_detection *det, size_t nt, size_t nd,
                                 elfm_error *err);

/* link_repair.c: the repair steps, run by elfm_link_step after the frame's
 * attachments and births; nd is the frame's detection count (their
 * det_id are relabelled when a track they joined changes). */

/* Step 1, predictions (link_predict.c). Fill lt->pred and lt->gate_um
 * for a frame at t_us (lt->missed set); at_rest: elfm_link_objects_at_rest
 * for this frame. */
void elfm_link_predict_track(const elfm_link_options *o, live_track *lt, int64_t t_us, int at_rest,
                             const double *common_vel);
/* With straight_gaps: the per-axis median of the long straight fits
 * (vel_um_per_ms) of the live tracks that have `history` points and were
 * seen in the frame before `frame`, into l->common_vel; l->has_common_vel
 * 0 with fewer than 3 such tracks. ELFM_ERR_NOMEM on out of memory. */
elfm_status elfm_link_common_velocity(elfm_linker *l, int64_t frame, elfm_error *err);
/* Most live tracks of >= 4 points slower than rest_speed_um_per_ms by
 * their straight-line fit, or none has 4 points yet. */
int elfm_link_objects_at_rest(const elfm_linker *l);
/* The rest hypothesis of a track dark for more than short_gap frames:
 * lt->has_rest, rest and rest_gate_um. */
void elfm_link_predict_rest(const elfm_link_options *o, live_track *lt, int64_t t_us, int at_rest);

/* Step 5, stitching (o.stitch_points > 0): each track that reached
 * stitch_points points in `frame` may be appended to a live track dark
 * since before its first point; the young track is then freed and removed
 * from l->live (order kept). */
elfm_status elfm_link_stitch(elfm_linker *l, int64_t frame, size_t nd, elfm_error *err);

/* Step 8, twins (o.twin_um > 0), at the start of a step for `frame`: each
 * live track that ends in it (dark for more than max_gap_frames) and has a
 * younger twin (elfm_link_options.twin_um) is joined to it: the twin's
 * slot carries on with the ending track's points, then the twin's after
 * them, and the ending track's slot is removed (the order kept). */
elfm_status elfm_link_join_twins(elfm_linker *l, int64_t frame, elfm_error *err);

/* Step 5b, late stitching (o.stitch_late_points > 0), with the twins: each
 * live track that ends in `frame` goes on as a young track on its recent
 * path too short for step 5 yet (elfm_link_options.stitch_late_points). */
elfm_status elfm_link_stitch_late(elfm_linker *l, int64_t frame, elfm_error *err);

/* Step 6, swap review (o.swap_points > 0): each gap closing still to be
 * reviewed whose tail has swap_points points is revisited once; the tails
 * of two live tracks are exchanged when that fits better. */
elfm_status elfm_link_review_swaps(elfm_linker *l, size_t nd, elfm_error *err);

/* Step 7, encounters (o.swap_points > 0, o.encounter_um > 0): of the
 * first nt live tracks (those before this frame's births), two within
 * encounter_um of each other in `frame` (the detection each took, or the
 * prediction of one that lost its object this frame) have met: the
 * encounter is recorded, or extended when they met in the frame before. */
elfm_status elfm_link_mark_encounters(elfm_linker *l, int64_t frame, size_t nt, elfm_error *err);

/* ... and once both have swap_points points after the encounter, their
 * tails are exchanged when that fits swap_ratio times better. */
elfm_status elfm_link_review_encounters(elfm_linker *l, int64_t frame, size_t nd, elfm_error *err);

#endif
