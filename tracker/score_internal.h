/* score_internal.h — private to tracker/score*.c: the types and helpers
 * that the parts of `eventlfm score` (SPEC §7; every definition is in
 * elfm_score.h) share. Not installed, not included elsewhere.
 *
 * Shape: score_io.c reads and checks the tables and builds (1) the frame
 * list from detections/tracks, (2) truth sampled at every frame where it
 * counts, stored both per object (for track distances) and per frame sorted
 * by x (for gated look-ups), the detections and the candidate tracks' real
 * points. score.c does (3) the per-frame detection matching and (5) the
 * stage velocity, and assembles the result; score_isbi.c does (4): the
 * candidates' gated matches with truth, pairing by Hungarian within
 * connected clusters (as the official evaluator clusters track pairs), and
 * the ISBI measures.
 * Gated look-ups use the x-sorted lists: only points with |dx| < eps can be
 * within the gate, so nothing here is quadratic in the number of objects.
 */
#ifndef ELFM_SCORE_INTERNAL_H
#define ELFM_SCORE_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "elfm_score.h"

/* The gate eps and the axial divisor kz (elfm_score.h, DISTANCE). */
typedef struct {
  double eps, kz;
} gate_t;

static inline double dist_aniso(const gate_t *g, double dx, double dy, double dz)
{
  double dzk = dz / g->kz;
  return sqrt(dx * dx + dy * dy + dzk * dzk);
}

/* The band of |z| a truth point at z_um falls in (elfm_score.h, BY DEPTH;
 * band_um > 0): the last band takes everything beyond. */
static inline int depth_band(double z_um, double band_um)
{
  const double k = floor(fabs(z_um) / band_um);
  return k < ELFM_SCORE_MAX_DEPTH_BANDS - 1 ? (int)k : ELFM_SCORE_MAX_DEPTH_BANDS - 1;
}

/* A sort key and the row or point it belongs to. */
typedef struct {
  double key;   /* sort key (id, or x) */
  size_t idx;   /* row / point index; ties keep file order */
} keyed_t;

/* Union-find over nodes 0..n-1 (path halving). */
static inline int uf_find(int *parent, int a)
{
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}
static inline void uf_union(int *parent, int a, int b)
{
  a = uf_find(parent, a);
  b = uf_find(parent, b);
  if (a != b) parent[a < b ? b : a] = a < b ? a : b;
}

/* First position in by_x[a..b) whose x is >= x0. */
static inline int64_t lower_x(const keyed_t *by_x, int64_t a, int64_t b, double x0)
{
  while (a < b) {
    int64_t mid = a + (b - a) / 2;
    if (by_x[mid].key < x0) a = mid + 1;
    else b = mid;
  }
  return a;
}

/* (1) The frames: slot i is frame index f_min + i. */
typedef struct {
  int64_t f_min;
  int n;             /* frames f_min .. f_min + n - 1 */
  double *t_us;      /* n; NaN where unknown (outside known frames: none) */
  /* each frame's window [t_start, t_end), from a frames table (NULL
   * without one; NaN for a frame the table does not list) */
  double *t_start_us, *t_end_us;
} frames_t;

/* Points at frame slots: the truth samples that count, the detections, the
 * candidate tracks' real points. */
typedef struct {
  int64_t n;         /* points */
  int *frame;        /* frame slot (0..n_frames-1) */
  double *x, *y, *z; /* um */
  /* detections with raw_x_um, raw_y_um, raw_z_um (track's, moved back by
   * their motion bias): the position as measured, which the motion
   * regression and the RMSE as measured read; NULL: x, y, z are */
  double *raw_x, *raw_y, *raw_z;
} points_t;

/* (2) Truth at the frames. */
typedef struct {
  int n_obj;
  /* the points that count; those of object k are [obj_off[k], obj_off[k+1])
   * in frame order */
  points_t pt;
  int64_t *obj_off;
  /* per frame slot f: fr_pt[fr_off[f] .. fr_off[f+1]) = {x, point index},
   * sorted by x (elfm_score_index_by_frame) */
  int64_t *fr_off;
  keyed_t *fr_pt;
  int64_t n_lit_then_dark; /* elfm_score_result.n_truth_lit_then_dark */
} truth_t;

/* Candidate tracks (elfm_score.h, TRACKS): their real points only. */
typedef struct {
  int n_tracks;
  int *off;    /* real points of track c: pt [off[c], off[c+1]) in frame order */
  points_t pt; /* smoothed positions */
} cands_t;

/* ---------------------------------------------------------------------- */
/* score.c: helpers the other parts share. */

/* The error of a failed allocation while scoring. */
elfm_status elfm_score_nomem(elfm_error *err);
/* qsort order of keyed_t: by key, then by idx (so ties keep file order). */
int elfm_score_keyed_cmp(const void *a, const void *b);
/* Room for a need-entry cost matrix in *cost (capacity *cap): it grows only
 * past the largest problem so far, so the per-frame and per-cluster
 * assignments stop allocating once they have seen their largest. */
elfm_status elfm_score_reserve_cost(double **cost, size_t *cap, size_t need, elfm_error *err);

/* ---------------------------------------------------------------------- */
/* score_io.c: the inputs, read and checked. Errors name file and line. */

/* Column indices of the required columns of detections (cd[5]: frame, t_us,
 * x_um, y_um, z_um) and tracks (ct[9]: track_id, frame, t_us, x_um, y_um,
 * z_um, raw_x_um, raw_y_um, raw_z_um); a NULL table is skipped. */
elfm_status elfm_score_columns(const elfm_table *dets, int *cd, const elfm_table *tracks,
                               int *ct, elfm_error *err);
/* The frame list (elfm_score.h, FRAMES); free with elfm_score_frames_free. */
void elfm_score_frames_free(frames_t *fr);
elfm_status elfm_score_frames_build(frames_t *fr, const elfm_table *dets, const int *cd,
                                    const elfm_table *trk, const int *ct, int64_t n_frames_hint,
                                    const elfm_table *frames_tab,
                                    elfm_error *err);
/* Frames whose t_us lies outside the truth's time range (its first to its
 * last sample over all ids) are not scored (elfm_score.h, FRAMES): their
 * t_us becomes NaN, so no truth, detection or track point there counts;
 * *n_unscored (may be NULL) gets how many. A truth without rows trims
 * nothing. */
elfm_status elfm_score_frames_trim(frames_t *fr, const elfm_table *tt, int *n_unscored,
                                   elfm_error *err);
/* Truth at the frames (elfm_score.h, TRUTH). Free with elfm_score_truth_free. */
elfm_status elfm_score_truth_build(truth_t *tr, const elfm_table *tt, const frames_t *fr,
                                   const elfm_score_options *o, elfm_error *err);
void elfm_score_truth_free(truth_t *t);
/* Number of truth ids with at least one sample that counts (bright, inside
 * the volume): used when the run produced no frame at all. */
elfm_status elfm_score_truth_ids_seen(const elfm_table *tt, const elfm_score_options *o,
                                      int *n_ids, elfm_error *err);
/* The rows of detections.csv at their frame slots (dp zeroed by the caller;
 * free with elfm_score_points_free). */
elfm_status elfm_score_detections_load(points_t *dp, const elfm_table *t, const int *c,
                                       const frames_t *fr, elfm_error *err);
/* Candidate tracks from tracks.csv (columns ct of elfm_score_columns); with
 * raw non-NULL (zeroed by the caller) also the real rows' raw positions, the
 * detections when there is no detections table. Free with elfm_score_cands_free. */
elfm_status elfm_score_cands_build(cands_t *cd, points_t *raw, const elfm_table *t,
                                   const int *c, const frames_t *fr, elfm_error *err);
void elfm_score_cands_free(cands_t *c);
void elfm_score_points_free(points_t *p);
/* Points grouped per frame slot and sorted by x within a frame, for gated
 * look-ups: entries [off[f], off[f+1]) of *by_x are {x, point index} of
 * frame f. off has n_frames + 1 entries, by_x p->n (+1); the caller frees
 * both. */
elfm_status elfm_score_index_by_frame(const points_t *p, int n_frames, int64_t **off_out,
                                      keyed_t **by_x_out, elfm_error *err);

/* ---------------------------------------------------------------------- */
/* score_isbi.c: the ISBI 2012 track measures (elfm_score.h, TRACKS) into
 * out's track fields; with band_um > 0 also each depth band's alpha_tracks
 * (elfm_score.h, BY DEPTH; out's bands already set up). */
elfm_status elfm_score_isbi_tracks(const truth_t *tr, const cands_t *cd, const gate_t *g,
                                   double band_um, elfm_score_result *out, elfm_error *err);
/* (4b) The identity diagnostics (elfm_score.h, IDENTITIES) into out's
 * alpha_identities, identity_fragments and identity_other_tracks. */
elfm_status elfm_score_identities(const truth_t *tr, const cands_t *cd, const gate_t *g,
                                  elfm_score_result *out, elfm_error *err);

#endif
