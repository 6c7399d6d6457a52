/* score_io.c — the scoring inputs read and checked (elfm_score.h, SPEC §7):
 * the required columns of truth.csv, tracks.csv and detections.csv, the
 * frame list, truth sampled at every frame where it counts, the detections
 * and the candidate tracks' real points. Each error names the table's file
 * and line.
 */
#include "score_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest frame-index span we accept: 5 M frames is 83 min at 1 kHz, far
 * beyond a simulated scene; beyond that an index is surely corrupt. The
 * frame list and its indexes take ~100 bytes per frame (0.5 GB here: at
 * the former 50 M, two rows of input reached 4.1 GB, fuzz_score). */
#define SCORE_MAX_FRAME_SPAN 5000000LL

/* Frame indices and ids must be integers well inside the double range. */
#define SCORE_MAX_INDEX 1e15

/* Required columns (elfm_score.h); the column index arrays c[] below
 * follow this order. */
static const char *const truth_cols[] = {"id", "t_us", "x_um", "y_um", "z_um", "brightness"};
static const char *const det_cols[] = {"frame", "t_us", "x_um", "y_um", "z_um"};
static const char *const frame_cols[] = {"frame", "t_us", "t_start_us", "t_end_us"};
static const char *const track_cols[] = {"track_id", "frame", "t_us", "x_um", "y_um",
                                         "z_um", "raw_x_um", "raw_y_um", "raw_z_um"};

static int is_index(double v) { return isfinite(v) && fabs(v) < SCORE_MAX_INDEX && v == floor(v); }

/* Order rows by an integer id column, file order within an id (stable).
 * Ids are usually small (0..objects): a counting sort is then linear, which
 * matters for truth.csv (10 samples per object per frame); otherwise qsort. */
static elfm_status group_by_id(const elfm_table *t, int col, keyed_t *ord, elfm_error *err)
{
  size_t n = t->n_rows;
  if (n == 0) return ELFM_OK;
  double lo = elfm_table_get(t, 0, col), hi = lo;
  for (size_t r = 1; r < n; r++) {
    double v = elfm_table_get(t, r, col);
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  if (hi - lo > 4.0 * (double)n + 1024.0) {
    for (size_t r = 0; r < n; r++) ord[r] = (keyed_t){elfm_table_get(t, r, col), r};
    qsort(ord, n, sizeof *ord, elfm_score_keyed_cmp);
    return ELFM_OK;
  }
  size_t range = (size_t)(hi - lo) + 1;
  size_t *start = calloc(range + 1, sizeof *start);
  if (!start) return elfm_score_nomem(err);
  for (size_t r = 0; r < n; r++) start[(size_t)(elfm_table_get(t, r, col) - lo) + 1]++;
  for (size_t k = 0; k < range; k++) start[k + 1] += start[k];
  for (size_t r = 0; r < n; r++) {
    double v = elfm_table_get(t, r, col);
    ord[start[(size_t)(v - lo)]++] = (keyed_t){v, r};
  }
  free(start);
  return ELFM_OK;
}

/* Rows of t grouped by the id in column c_id (group_by_id) into *ord
 * (n_rows entries; the caller frees it). Within an id the value in column
 * c_seq must increase (truth times, a track's frames); where it does not,
 * the error is ELFM_ERR_FORMAT at the offending row's line, worded by
 * unsorted_fmt, a format that takes the id, the value, the value before it
 * (all %.0f) and that row's line (%lld). One check for both tables. */
static elfm_status group_rows(const elfm_table *t, int c_id, int c_seq, const char *unsorted_fmt,
                              keyed_t **ord, elfm_error *err)
{
  size_t n = t->n_rows;
  keyed_t *o = malloc((n ? n : 1) * sizeof *o);
  if (!o) return elfm_score_nomem(err);
  elfm_status s = group_by_id(t, c_id, o, err);
  if (s != ELFM_OK) { free(o); return s; }
  for (size_t i = 1; i < n; i++) {
    double v0 = elfm_table_get(t, o[i - 1].idx, c_seq), v1 = elfm_table_get(t, o[i].idx, c_seq);
    if (o[i].key == o[i - 1].key && !(v1 > v0)) {
      elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[o[i].idx], unsorted_fmt,
                          o[i].key, v1, v0, (long long)t->line[o[i - 1].idx]);
      free(o);
      return ELFM_ERR_FORMAT;
    }
  }
  *ord = o;
  return ELFM_OK;
}

/* Fetch a required finite value or fail naming file:line and column. */
static elfm_status get_req(const elfm_table *t, size_t r, int col, const char *name,
                           double *out, elfm_error *err)
{
  double v = elfm_table_get(t, r, col);
  if (!isfinite(v))
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                               "column %s is empty (a value is required here)", name);
  *out = v;
  return ELFM_OK;
}

/* The checks every row of truth.csv and tracks.csv passes first: columns
 * c[0..n_req) hold values, and column c[0] (the id) is an integer. */
static elfm_status check_row(const elfm_table *t, size_t r, const int *c,
                             const char *const *names, int n_req, elfm_error *err)
{
  double v;
  elfm_status s;
  for (int k = 0; k < n_req; k++)
    if ((s = get_req(t, r, c[k], names[k], &v, err)) != ELFM_OK) return s;
  if (!is_index(elfm_table_get(t, r, c[0])))
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                               "column %s must be an integer", names[0]);
  return ELFM_OK;
}

elfm_status elfm_score_columns(const elfm_table *dets, int *cd, const elfm_table *tracks,
                               int *ct, elfm_error *err)
{
  elfm_status s;
  if (dets && (s = elfm_table_require(dets, det_cols, 5, cd, err)) != ELFM_OK) return s;
  if (tracks && (s = elfm_table_require(tracks, track_cols, 9, ct, err)) != ELFM_OK) return s;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* (1) Frames */

static elfm_status frames_scan(const elfm_table *t, int c_frame, int c_t, int64_t *fmin,
                               int64_t *fmax, elfm_error *err)
{
  for (size_t r = 0; r < t->n_rows; r++) {
    double f = elfm_table_get(t, r, c_frame), tu;
    if (!is_index(f))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "column frame must be an integer frame index");
    elfm_status s = get_req(t, r, c_t, "t_us", &tu, err);
    if (s != ELFM_OK) return s;
    if ((int64_t)f < *fmin) *fmin = (int64_t)f;
    if ((int64_t)f > *fmax) *fmax = (int64_t)f;
  }
  return ELFM_OK;
}

static elfm_status frames_fill(frames_t *fr, const elfm_table *t, int c_frame, int c_t,
                               size_t *src_row, const elfm_table **src_tab, elfm_error *err)
{
  for (size_t r = 0; r < t->n_rows; r++) {
    int64_t f = (int64_t)elfm_table_get(t, r, c_frame) - fr->f_min;
    double tu = elfm_table_get(t, r, c_t);
    if (fr->t_start_us && (f < 0 || f >= fr->n || isnan(fr->t_start_us[f])))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "frame %lld is not in the frame list", (long long)(f + fr->f_min));
    if (isnan(fr->t_us[f])) {
      fr->t_us[f] = tu;
      src_row[f] = r;
      src_tab[f] = t;
    } else if (fabs(fr->t_us[f] - tu) > 0.5) { /* times are integer us */
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "frame %lld has t_us %.0f here but %.0f at %s:%lld",
                                 (long long)(f + fr->f_min), tu, fr->t_us[f],
                                 src_tab[f]->path, (long long)src_tab[f]->line[src_row[f]]);
    }
  }
  return ELFM_OK;
}

void elfm_score_frames_free(frames_t *fr)
{
  free(fr->t_us);
  free(fr->t_start_us);
  free(fr->t_end_us);
  fr->t_us = fr->t_start_us = fr->t_end_us = NULL;
}

/* The frame list's own checks (elfm_score.h, frames): required values,
 * integer frames, index and time increasing, t_start <= t_us <= t_end and
 * t_start < t_end. Its span goes into fmin / fmax. */
static elfm_status frames_table_check(const elfm_table *ft, const int *cf, int64_t *fmin,
                                      int64_t *fmax, elfm_error *err)
{
  double prev_f = -INFINITY, prev_t = -INFINITY;
  for (size_t r = 0; r < ft->n_rows; r++) {
    double v[4] = {0, 0, 0, 0};
    elfm_status s;
    for (int k = 0; k < 4; k++)
      if ((s = get_req(ft, r, cf[k], frame_cols[k], &v[k], err)) != ELFM_OK) return s;
    if (!is_index(v[0]))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, ft->path, ft->line[r],
                                 "column frame must be an integer frame index");
    if (!(v[0] > prev_f) || !(v[1] > prev_t))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, ft->path, ft->line[r],
                                 "frame %.0f (t_us %.0f) does not follow the previous row's: "
                                 "frames and their times must increase", v[0], v[1]);
    if (!(v[2] <= v[1] && v[1] <= v[3] && v[2] < v[3]))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, ft->path, ft->line[r],
                                 "frame %.0f: t_us %.0f is not inside its window [%.0f, %.0f)",
                                 v[0], v[1], v[2], v[3]);
    prev_f = v[0];
    prev_t = v[1];
    if ((int64_t)v[0] < *fmin) *fmin = (int64_t)v[0];
    if ((int64_t)v[0] > *fmax) *fmax = (int64_t)v[0];
  }
  return ELFM_OK;
}

elfm_status elfm_score_frames_build(frames_t *fr, const elfm_table *dets, const int *cd,
                                    const elfm_table *trk, const int *ct, int64_t n_frames_hint,
                                    const elfm_table *ft, elfm_error *err)
{
  int64_t fmin = INT64_MAX, fmax = INT64_MIN;
  elfm_status s;
  int cf[4];
  if (ft) {
    if ((s = elfm_table_require(ft, frame_cols, 4, cf, err)) != ELFM_OK) return s;
    if ((s = frames_table_check(ft, cf, &fmin, &fmax, err)) != ELFM_OK) return s;
    n_frames_hint = 0; /* the list says which frames there were */
  }
  if (dets && (s = frames_scan(dets, cd[0], cd[1], &fmin, &fmax, err)) != ELFM_OK) return s;
  if (trk && (s = frames_scan(trk, ct[1], ct[2], &fmin, &fmax, err)) != ELFM_OK) return s;
  fr->n = 0;
  fr->f_min = 0;
  if (fmin > fmax) return ELFM_OK; /* no rows at all: nothing to score */
  /* The run's frames 0 .. n_frames_hint - 1 all count, also those before
   * the first and after the last row (times extrapolated below). */
  int known_lo = 0, known_hi = 0;
  int64_t kmin = fmin, kmax = fmax;
  if (n_frames_hint > 0) {
    if (fmin > 0) fmin = 0;
    if (fmax < n_frames_hint - 1) fmax = n_frames_hint - 1;
  }
  if (fmax - fmin + 1 > SCORE_MAX_FRAME_SPAN)
    return elfm_error_set(err, ELFM_ERR_RANGE, dets ? dets->path : trk->path, -1,
                          "frame indices span %lld..%lld: more than %lld frames",
                          (long long)fmin, (long long)fmax, (long long)SCORE_MAX_FRAME_SPAN);
  fr->f_min = fmin;
  fr->n = (int)(fmax - fmin + 1);
  fr->t_us = malloc((size_t)fr->n * sizeof *fr->t_us);
  size_t *src_row = malloc((size_t)fr->n * sizeof *src_row);
  const elfm_table **src_tab = malloc((size_t)fr->n * sizeof *src_tab);
  if (!fr->t_us || !src_row || !src_tab) {
    free(src_row);
    free(src_tab);
    return elfm_score_nomem(err);
  }
  for (int i = 0; i < fr->n; i++) fr->t_us[i] = NAN;
  s = ELFM_OK;
  if (ft) {
    fr->t_start_us = malloc((size_t)fr->n * sizeof *fr->t_start_us);
    fr->t_end_us = malloc((size_t)fr->n * sizeof *fr->t_end_us);
    if (!fr->t_start_us || !fr->t_end_us) s = elfm_score_nomem(err);
    for (int i = 0; s == ELFM_OK && i < fr->n; i++) fr->t_start_us[i] = fr->t_end_us[i] = NAN;
    for (size_t r = 0; s == ELFM_OK && r < ft->n_rows; r++) {
      int64_t f = (int64_t)elfm_table_get(ft, r, cf[0]) - fr->f_min;
      fr->t_us[f] = elfm_table_get(ft, r, cf[1]);
      fr->t_start_us[f] = elfm_table_get(ft, r, cf[2]);
      fr->t_end_us[f] = elfm_table_get(ft, r, cf[3]);
      src_row[f] = r;
      src_tab[f] = ft;
    }
  }
  if (s == ELFM_OK && dets) s = frames_fill(fr, dets, cd[0], cd[1], src_row, src_tab, err);
  if (s == ELFM_OK && trk) s = frames_fill(fr, trk, ct[1], ct[2], src_row, src_tab, err);
  /* Known frames must be in time order; unknown ones in between are
   * interpolated from their known neighbours. */
  int prev = -1;
  for (int i = 0; s == ELFM_OK && i < fr->n; i++) {
    if (isnan(fr->t_us[i])) continue;
    if (prev >= 0) {
      if (!(fr->t_us[i] > fr->t_us[prev])) {
        s = elfm_error_set_line(err, ELFM_ERR_FORMAT, src_tab[i]->path,
                                src_tab[i]->line[src_row[i]],
                                "frame %lld (t_us %.0f) is not later than frame %lld "
                                "(t_us %.0f): frame times must increase with the index",
                                (long long)(i + fr->f_min), fr->t_us[i],
                                (long long)(prev + fr->f_min), fr->t_us[prev]);
        break;
      }
      for (int k = prev + 1; k < i; k++)
        fr->t_us[k] = fr->t_us[prev] + (fr->t_us[i] - fr->t_us[prev]) *
                                           (double)(k - prev) / (double)(i - prev);
    }
    prev = i;
  }
  /* With a frame list, a frame it does not list did not exist: no time */
  for (int i = 0; s == ELFM_OK && ft && i < fr->n; i++)
    if (isnan(fr->t_start_us[i])) fr->t_us[i] = NAN;
  /* Frames outside the known range (only with a hint): extrapolate with the
   * mean spacing of the known frames; with a single known frame there is no
   * spacing and they stay unknown (NaN: never scored). */
  known_lo = (int)(kmin - fr->f_min);
  known_hi = (int)(kmax - fr->f_min);
  if (s == ELFM_OK && known_hi > known_lo) {
    double step = (fr->t_us[known_hi] - fr->t_us[known_lo]) / (double)(known_hi - known_lo);
    for (int i = 0; i < known_lo; i++)
      fr->t_us[i] = fr->t_us[known_lo] - step * (double)(known_lo - i);
    for (int i = known_hi + 1; i < fr->n; i++)
      fr->t_us[i] = fr->t_us[known_hi] + step * (double)(i - known_hi);
  }
  free(src_row);
  free(src_tab);
  return s;
}

elfm_status elfm_score_frames_trim(frames_t *fr, const elfm_table *tt, int *n_unscored,
                                   elfm_error *err)
{
  int c[6];
  elfm_status s = elfm_table_require(tt, truth_cols, 6, c, err);
  if (s != ELFM_OK) return s;
  int n = 0;
  if (tt->n_rows > 0) {
    double t_lo = INFINITY, t_hi = -INFINITY;
    for (size_t r = 0; r < tt->n_rows; r++) {
      double t = elfm_table_get(tt, r, c[1]);
      if (t < t_lo) t_lo = t;
      if (t > t_hi) t_hi = t;
    }
    /* NaN times (checked as errors later, in the truth) compare false and
     * trim nothing here. */
    for (int i = 0; i < fr->n; i++)
      if (fr->t_us[i] < t_lo || fr->t_us[i] > t_hi) {
        fr->t_us[i] = NAN;
        n++;
      }
  }
  if (n_unscored) *n_unscored = n;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* Points */

void elfm_score_points_free(points_t *p)
{
  free(p->frame);
  free(p->x);
  free(p->y);
  free(p->z);
  free(p->raw_x);
  free(p->raw_y);
  free(p->raw_z);
}

/* Room for cap points (at least 1), contents kept. On failure the arrays
 * that did grow stay in p, so elfm_score_points_free still frees everything. */
static elfm_status points_reserve(points_t *p, size_t cap, elfm_error *err)
{
  size_t m = cap ? cap : 1;
  int *f = realloc(p->frame, m * sizeof *f);
  if (f) p->frame = f;
  double *x = realloc(p->x, m * sizeof *x);
  if (x) p->x = x;
  double *y = realloc(p->y, m * sizeof *y);
  if (y) p->y = y;
  double *z = realloc(p->z, m * sizeof *z);
  if (z) p->z = z;
  if (!f || !x || !y || !z) return elfm_score_nomem(err);
  return ELFM_OK;
}

elfm_status elfm_score_index_by_frame(const points_t *p, int n_frames, int64_t **off_out,
                                      keyed_t **by_x_out, elfm_error *err)
{
  int64_t *off = calloc((size_t)n_frames + 1, sizeof *off);
  keyed_t *by_x = malloc(((size_t)p->n + 1) * sizeof *by_x);
  int64_t *fill = malloc(((size_t)n_frames + 1) * sizeof *fill);
  if (!off || !by_x || !fill) {
    free(off);
    free(by_x);
    free(fill);
    return elfm_score_nomem(err);
  }
  for (int64_t i = 0; i < p->n; i++) off[p->frame[i] + 1]++;
  for (int f = 0; f < n_frames; f++) off[f + 1] += off[f];
  memcpy(fill, off, ((size_t)n_frames + 1) * sizeof *fill);
  for (int64_t i = 0; i < p->n; i++) by_x[fill[p->frame[i]]++] = (keyed_t){p->x[i], (size_t)i};
  free(fill);
  for (int f = 0; f < n_frames; f++)
    qsort(by_x + off[f], (size_t)(off[f + 1] - off[f]), sizeof *by_x, elfm_score_keyed_cmp);
  *off_out = off;
  *by_x_out = by_x;
  return ELFM_OK;
}

elfm_status elfm_score_detections_load(points_t *dp, const elfm_table *t, const int *c,
                                       const frames_t *fr, elfm_error *err)
{
  elfm_status s = points_reserve(dp, t->n_rows, err);
  if (s != ELFM_OK) return s;
  /* track's detections.csv has the measured positions beside: the three
   * columns or none, and where given, values on every row */
  static const char *const raw_names[3] = {"raw_x_um", "raw_y_um", "raw_z_um"};
  int cr[3], n_raw = 0;
  for (int a = 0; a < 3; a++) n_raw += (cr[a] = elfm_table_col(t, raw_names[a])) >= 0;
  if (n_raw != 0 && n_raw != 3)
    return elfm_error_set(err, ELFM_ERR_FORMAT, t->path, -1,
                          "columns raw_x_um, raw_y_um, raw_z_um: all three or none (%d found)", n_raw);
  if (n_raw) {
    const size_t m = t->n_rows ? t->n_rows : 1;
    dp->raw_x = malloc(m * sizeof *dp->raw_x);
    dp->raw_y = malloc(m * sizeof *dp->raw_y);
    dp->raw_z = malloc(m * sizeof *dp->raw_z);
    if (!dp->raw_x || !dp->raw_y || !dp->raw_z) return elfm_score_nomem(err);
  }
  for (size_t r = 0; r < t->n_rows; r++) {
    double v[3] = {0, 0, 0}, rv[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++)
      if ((s = get_req(t, r, c[2 + a], det_cols[2 + a], &v[a], err)) != ELFM_OK) return s;
    for (int a = 0; n_raw && a < 3; a++)
      if ((s = get_req(t, r, cr[a], raw_names[a], &rv[a], err)) != ELFM_OK) return s;
    const int f = (int)((int64_t)elfm_table_get(t, r, c[0]) - fr->f_min);
    if (isnan(fr->t_us[f])) continue; /* outside the truth's time range */
    dp->frame[dp->n] = f;
    dp->x[dp->n] = v[0];
    dp->y[dp->n] = v[1];
    dp->z[dp->n] = v[2];
    if (dp->raw_x) {
      dp->raw_x[dp->n] = rv[0];
      dp->raw_y[dp->n] = rv[1];
      dp->raw_z[dp->n] = rv[2];
    }
    dp->n++;
  }
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* (2) Truth at the frames */

void elfm_score_truth_free(truth_t *t)
{
  elfm_score_points_free(&t->pt);
  free(t->obj_off);
  free(t->fr_off);
  free(t->fr_pt);
}

static int inside(const elfm_score_options *o, double x, double y, double z)
{
  if (!o->have_bounds) return 1;
  return fabs(x) <= o->x_half_um && fabs(y) <= o->y_half_um && z >= o->z_min_um &&
         z <= o->z_max_um;
}

/* The time of the frame before f, or where the frames' spacing puts it for
 * the first frame; NaN where neither is known. */
static double prev_frame_t(const frames_t *fr, int f, int f_lo, int f_hi)
{
  if (f > f_lo) return fr->t_us[f - 1];
  if (f < f_hi) return 2 * fr->t_us[f] - fr->t_us[f + 1];
  return NAN;
}

/* The samples of ord[*q .. j) with t0 < t_us <= t1, and how many of them
 * are lit: *q first moves past those at or before t0 (t0 never decreases
 * between calls for one object, so the walk is once over its samples). */
static void samples_in(const elfm_table *tt, const int *c, const keyed_t *ord, size_t *q, size_t j,
                       double t0, double t1, int64_t *n_in, int64_t *n_lit)
{
  while (*q < j && elfm_table_get(tt, ord[*q].idx, c[1]) <= t0) (*q)++;
  *n_in = *n_lit = 0;
  for (size_t k = *q; k < j && elfm_table_get(tt, ord[k].idx, c[1]) <= t1; k++) {
    (*n_in)++;
    *n_lit += elfm_table_get(tt, ord[k].idx, c[5]) > 0;
  }
}

elfm_status elfm_score_truth_build(truth_t *tr, const elfm_table *tt, const frames_t *fr,
                                   const elfm_score_options *o, elfm_error *err)
{
  int c[6];
  elfm_status s = elfm_table_require(tt, truth_cols, 6, c, err);
  if (s != ELFM_OK) return s;
  memset(tr, 0, sizeof *tr);
  size_t n = tt->n_rows;
  /* Validate every row. */
  for (size_t r = 0; r < n; r++) {
    if ((s = check_row(tt, r, c, truth_cols, 6, err)) != ELFM_OK) return s;
    if (elfm_table_get(tt, r, c[5]) < 0)
      return elfm_error_set_line(err, ELFM_ERR_RANGE, tt->path, tt->line[r],
                                 "brightness %g is negative", elfm_table_get(tt, r, c[5]));
  }
  /* Group rows per id (stable: file order within an id), times increasing. */
  keyed_t *ord;
  s = group_rows(tt, c[0], c[1],
                 "truth for id %.0f is not sorted by time: t_us %.0f follows %.0f (line %lld)",
                 &ord, err);
  if (s != ELFM_OK) return s;
  int n_obj = 0;
  for (size_t i = 0; i < n; i++) n_obj += (i == 0 || ord[i].key != ord[i - 1].key);
  tr->n_obj = n_obj;
  tr->obj_off = malloc(((size_t)n_obj + 1) * sizeof *tr->obj_off);
  if (!tr->obj_off) { free(ord); return elfm_score_nomem(err); }
  int64_t cap = 0;
  size_t i = 0;
  int k = 0;
  s = ELFM_OK;
  /* The frames with a time form one block [f_lo, f_hi] in increasing time
   * (elfm_score_frames_build); outside it (a single known frame and a frame
   * count hint) times are unknown and nothing counts. */
  int f_lo = 0, f_hi = fr->n - 1;
  const int literal = !o->window_frames && !(o->window_us > 0);
  while (f_lo < fr->n && isnan(fr->t_us[f_lo])) f_lo++;
  while (f_hi >= f_lo && isnan(fr->t_us[f_hi])) f_hi--;
  while (i < n && s == ELFM_OK) {
    size_t j = i;
    while (j < n && ord[j].key == ord[i].key) j++;
    tr->obj_off[k] = tr->pt.n;
    /* Samples ord[i..j) of this object, increasing t. Walk the frames that
     * fall inside its time range with one cursor. */
    double t_first = elfm_table_get(tt, ord[i].idx, c[1]);
    double t_last = elfm_table_get(tt, ord[j - 1].idx, c[1]);
    size_t cur = i, wcur = i;
    /* the first frame at or after t_first (binary search: each object
     * visits only the frames of its own time range, not all of them) */
    int lo = f_lo, hi = f_hi + 1;
    while (lo < hi) {
      int mid = lo + (hi - lo) / 2;
      if (fr->t_us[mid] < t_first) lo = mid + 1;
      else hi = mid;
    }
    for (int f = lo; f <= f_hi && s == ELFM_OK; f++) {
      double t = fr->t_us[f];
      if (t > t_last) break;
      if (!(t >= t_first)) continue;
      while (cur + 1 < j && elfm_table_get(tt, ord[cur + 1].idx, c[1]) < t) cur++;
      /* Window rule (elfm_score.h, window_us): bright for at least half of
       * the samples in (t - window, t]; samples are dense (<= 100 us, SPEC
       * §6). With no sample inside the window, the value at t decides. */
      int window_votes = -1; /* -1: no vote, 0 dark, 1 lit */
      if (o->window_frames && fr->t_start_us) {
        /* the frame's own window [t_start, t_end) (elfm_score.h) */
        const double w0 = fr->t_start_us[f], w1 = fr->t_end_us[f];
        while (wcur < j && elfm_table_get(tt, ord[wcur].idx, c[1]) < w0) wcur++;
        int64_t n_in = 0, n_lit = 0;
        for (size_t q = wcur; q < j && elfm_table_get(tt, ord[q].idx, c[1]) < w1; q++) {
          n_in++;
          n_lit += elfm_table_get(tt, ord[q].idx, c[5]) > 0;
        }
        if (n_in > 0) {
          window_votes = 2 * n_lit >= n_in;
        } else {
          /* A window shorter than the sampling (one cut short just before
           * a trigger edge): the latest sample before it holds. Neither
           * the brightness interpolated inside it nor the sample nearest
           * to it will do: a window that ends at a rising edge lies
           * between a dark and a lit sample, and both would light it when
           * the edge is just before a sample (blink seed 7, 4 us). */
          size_t q = wcur > i ? wcur - 1 : i;
          window_votes = elfm_table_get(tt, ord[q].idx, c[5]) > 0;
        }
      } else if (o->window_us > 0) {
        int64_t n_in, n_lit;
        samples_in(tt, c, ord, &wcur, j, t - o->window_us, t, &n_in, &n_lit);
        if (n_in > 0) window_votes = 2 * n_lit >= n_in;
      }
      size_t ra = ord[cur].idx, rb = cur + 1 < j ? ord[cur + 1].idx : ra;
      double ta = elfm_table_get(tt, ra, c[1]), tb = elfm_table_get(tt, rb, c[1]);
      double w = tb > ta ? (t - ta) / (tb - ta) : 0.0;
      double val[4];
      for (int q = 0; q < 4; q++) {
        double a = elfm_table_get(tt, ra, c[2 + q]), b = elfm_table_get(tt, rb, c[2 + q]);
        /* on a sample, its value exactly (a + 1 * (b - a) may round off b) */
        val[q] = t == ta ? a : t == tb ? b : a + w * (b - a);
      }
      int lit = window_votes >= 0 ? window_votes : val[3] > 0.0;
      if (!lit) {
        /* under the literal rule, was it lit since the frame before
         * (n_truth_lit_then_dark)? wcur serves no window rule then */
        const double t_prev = prev_frame_t(fr, f, f_lo, f_hi);
        int64_t n_in, n_lit = 0;
        if (literal && t_prev < t && inside(o, val[0], val[1], val[2]))
          samples_in(tt, c, ord, &wcur, j, t_prev, t, &n_in, &n_lit);
        tr->n_lit_then_dark += n_lit > 0;
        continue;
      }
      if (!inside(o, val[0], val[1], val[2])) continue;
      if (tr->pt.n == cap) {
        /* A cap on the points (elfm_score_options.max_truth_points): a few
         * thousand ids over a long frame span would otherwise ask for
         * terabytes. */
        const int64_t most = o->max_truth_points;
        if (cap >= most) {
          s = elfm_error_set(err, ELFM_ERR_RANGE, tt->path, -1,
                             "the truth counts at more than %lld object-frames (%d objects, "
                             "%d frames): score a shorter stretch",
                             (long long)most, n_obj, fr->n);
          break;
        }
        cap = cap ? 2 * cap : 1024;
        if (cap > most) cap = most;
        if ((s = points_reserve(&tr->pt, (size_t)cap, err)) != ELFM_OK) break;
      }
      tr->pt.frame[tr->pt.n] = f;
      tr->pt.x[tr->pt.n] = val[0];
      tr->pt.y[tr->pt.n] = val[1];
      tr->pt.z[tr->pt.n] = val[2];
      tr->pt.n++;
    }
    k++;
    i = j;
  }
  free(ord);
  if (s != ELFM_OK) return s;
  tr->obj_off[n_obj] = tr->pt.n;

  /* Per-frame index, sorted by x within a frame. */
  return elfm_score_index_by_frame(&tr->pt, fr->n, &tr->fr_off, &tr->fr_pt, err);
}

elfm_status elfm_score_truth_ids_seen(const elfm_table *tt, const elfm_score_options *o,
                                      int *n_ids, elfm_error *err)
{
  int c[6];
  elfm_status s = elfm_table_require(tt, truth_cols, 6, c, err);
  if (s != ELFM_OK) return s;
  double *ids = malloc((tt->n_rows + 1) * sizeof *ids);
  if (!ids) return elfm_score_nomem(err);
  size_t n = 0;
  for (size_t r = 0; r < tt->n_rows; r++)
    if (elfm_table_get(tt, r, c[5]) > 0 &&
        inside(o, elfm_table_get(tt, r, c[2]), elfm_table_get(tt, r, c[3]),
               elfm_table_get(tt, r, c[4])))
      ids[n++] = elfm_table_get(tt, r, c[0]);
  keyed_t *k = malloc((n + 1) * sizeof *k);
  if (!k) { free(ids); return elfm_score_nomem(err); }
  for (size_t i = 0; i < n; i++) k[i] = (keyed_t){ids[i], i};
  qsort(k, n, sizeof *k, elfm_score_keyed_cmp);
  int u = 0;
  for (size_t i = 0; i < n; i++) u += (i == 0 || k[i].key != k[i - 1].key);
  free(k);
  free(ids);
  *n_ids = u;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* (4) Candidate tracks */

void elfm_score_cands_free(cands_t *c)
{
  free(c->off);
  elfm_score_points_free(&c->pt);
}

/* Columns: 0 track_id 1 frame 2 t_us 3 x 4 y 5 z 6 raw_x 7 raw_y 8 raw_z */
/* A real point of a track (raw values present) at a scored frame. */
static int row_real(const elfm_table *t, size_t r, const int *c, const frames_t *fr)
{
  return isfinite(elfm_table_get(t, r, c[6])) &&
         !isnan(fr->t_us[(int64_t)elfm_table_get(t, r, c[1]) - fr->f_min]);
}

elfm_status elfm_score_cands_build(cands_t *cd, points_t *raw, const elfm_table *t,
                                   const int *c, const frames_t *fr, elfm_error *err)
{
  memset(cd, 0, sizeof *cd);
  size_t n = t->n_rows;
  elfm_status s;
  for (size_t r = 0; r < n; r++) {
    if ((s = check_row(t, r, c, track_cols, 6, err)) != ELFM_OK) return s;
    int n_raw = 0;
    for (int k = 6; k < 9; k++) n_raw += isfinite(elfm_table_get(t, r, c[k])) ? 1 : 0;
    if (n_raw != 0 && n_raw != 3)
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "raw_x_um, raw_y_um, raw_z_um must be all present (a detection) "
                                 "or all empty (a gap-closing fill)");
  }
  keyed_t *ord;
  s = group_rows(t, c[0], c[1],
                 "track %.0f: frame %.0f follows frame %.0f (line %lld); a track's rows must "
                 "be in increasing frame order, one per frame",
                 &ord, err);
  if (s != ELFM_OK) return s;
  int n_tracks = 0;
  /* Count tracks with at least one real point. */
  for (size_t i = 0; i < n;) {
    size_t j = i;
    int real = 0;
    while (j < n && ord[j].key == ord[i].key) real |= row_real(t, ord[j++].idx, c, fr);
    n_tracks += real;
    i = j;
  }
  cd->n_tracks = n_tracks;
  cd->off = malloc(((size_t)n_tracks + 1) * sizeof *cd->off);
  if (!cd->off) { free(ord); return elfm_score_nomem(err); }
  if ((s = points_reserve(&cd->pt, n, err)) != ELFM_OK ||
      (raw && (s = points_reserve(raw, n, err)) != ELFM_OK)) { free(ord); return s; }
  int k = 0, np = 0;
  for (size_t i = 0; i < n;) {
    size_t j = i;
    int start = np;
    while (j < n && ord[j].key == ord[i].key) {
      size_t r = ord[j++].idx;
      if (!row_real(t, r, c, fr)) continue;
      int f = (int)((int64_t)elfm_table_get(t, r, c[1]) - fr->f_min);
      cd->pt.frame[np] = f;
      cd->pt.x[np] = elfm_table_get(t, r, c[3]);
      cd->pt.y[np] = elfm_table_get(t, r, c[4]);
      cd->pt.z[np] = elfm_table_get(t, r, c[5]);
      np++;
      if (raw) {
        raw->frame[raw->n] = f;
        raw->x[raw->n] = elfm_table_get(t, r, c[6]);
        raw->y[raw->n] = elfm_table_get(t, r, c[7]);
        raw->z[raw->n] = elfm_table_get(t, r, c[8]);
        raw->n++;
      }
    }
    if (np > start) cd->off[k++] = start;
    i = j;
  }
  cd->off[n_tracks] = np;
  cd->pt.n = np;
  free(ord);
  return ELFM_OK;
}
