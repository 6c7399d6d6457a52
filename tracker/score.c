/* score.c — detections and tracks against simulator truth (see elfm_score.h
 * for every definition; this file follows it step by step).
 *
 * Shape: (1) the frame list from detections/tracks, (2) truth sampled at
 * every frame where it counts, stored both per object (for track distances)
 * and per frame sorted by x (for gated look-ups), (3) per-frame detection
 * matching, (4) candidate tracks, their gated matches with truth, pairing by
 * Hungarian within connected clusters (as the official evaluator clusters
 * track pairs), and the ISBI measures, (5) the stage velocity.
 * Gated look-ups use the x-sorted lists: only points with |dx| < eps can be
 * within the gate, so nothing here is quadratic in the number of objects.
 */
#include "elfm_score.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest frame-index span we accept: 50 M frames is 14 h at 1 kHz; beyond
 * that an index is surely corrupt, and we would allocate per frame. */
#define SCORE_MAX_FRAME_SPAN 50000000LL
/* Frame indices and ids must be integers well inside the double range. */
#define SCORE_MAX_INDEX 1e15

/* Required columns (elfm_score.h); the column index arrays c[] below
 * follow this order. */
static const char *const truth_cols[] = {"id", "t_us", "x_um", "y_um", "z_um", "brightness"};
static const char *const det_cols[] = {"frame", "t_us", "x_um", "y_um", "z_um"};
static const char *const track_cols[] = {"track_id", "frame", "t_us", "x_um", "y_um",
                                         "z_um", "raw_x_um", "raw_y_um", "raw_z_um"};

typedef struct {
  double eps, kz;
} gate_t;

static double dist_aniso(const gate_t *g, double dx, double dy, double dz)
{
  double dzk = dz / g->kz;
  return sqrt(dx * dx + dy * dy + dzk * dzk);
}

void elfm_score_options_default(elfm_score_options *o)
{
  memset(o, 0, sizeof *o);
  o->eps_um = 4.0; /* SPEC §7 */
  o->kz = 4.0;     /* SPEC §7 */
  o->n_frames_hint = 0;
}

void elfm_score_options_set_calib(elfm_score_options *o, const elfm_calib *c)
{
  /* SPEC §3: voxel X sits at (X - (W-1)/2) * um_per_px, X = 0..W-1. */
  o->have_bounds = 1;
  o->x_half_um = 0.5 * (double)(c->view_w_px - 1) * c->um_per_px;
  o->y_half_um = 0.5 * (double)(c->view_h_px - 1) * c->um_per_px;
  o->z_min_um = c->z_min_um;
  o->z_max_um = c->z_max_um;
}

/* ---------------------------------------------------------------------- */
/* Small helpers */

static int is_index(double v) { return isfinite(v) && fabs(v) < SCORE_MAX_INDEX && v == floor(v); }

typedef struct {
  double key;   /* sort key (id, or x) */
  size_t idx;   /* row / point index; ties keep file order */
} keyed_t;

static elfm_status nomem(elfm_error *err);

static int keyed_cmp(const void *a, const void *b)
{
  const keyed_t *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->idx < y->idx ? -1 : x->idx > y->idx;
}

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
    qsort(ord, n, sizeof *ord, keyed_cmp);
    return ELFM_OK;
  }
  size_t range = (size_t)(hi - lo) + 1;
  size_t *start = calloc(range + 1, sizeof *start);
  if (!start) return nomem(err);
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
 * c_seq must increase (truth times, a track's frames): *bad receives the
 * first position in *ord whose value does not exceed its predecessor's,
 * or n_rows when there is none; the caller words the error. */
static elfm_status group_rows(const elfm_table *t, int c_id, int c_seq, keyed_t **ord,
                              size_t *bad, elfm_error *err)
{
  size_t n = t->n_rows;
  keyed_t *o = malloc((n ? n : 1) * sizeof *o);
  if (!o) return nomem(err);
  elfm_status s = group_by_id(t, c_id, o, err);
  if (s != ELFM_OK) { free(o); return s; }
  *bad = n;
  for (size_t i = 1; i < n; i++)
    if (o[i].key == o[i - 1].key &&
        !(elfm_table_get(t, o[i].idx, c_seq) > elfm_table_get(t, o[i - 1].idx, c_seq))) {
      *bad = i;
      break;
    }
  *ord = o;
  return ELFM_OK;
}

/* Union-find over nodes 0..n-1 (path halving). */
static int uf_find(int *parent, int a)
{
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}
static void uf_union(int *parent, int a, int b)
{
  a = uf_find(parent, a);
  b = uf_find(parent, b);
  if (a != b) parent[a < b ? b : a] = a < b ? a : b;
}

static elfm_status nomem(elfm_error *err)
{
  return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory while scoring");
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

/* Room for a need-entry cost matrix in *cost (capacity *cap): it grows only
 * past the largest problem so far, so the per-frame and per-cluster
 * assignments stop allocating once they have seen their largest. */
static elfm_status reserve_cost(double **cost, size_t *cap, size_t need, elfm_error *err)
{
  if (need <= *cap) return ELFM_OK;
  double *nb = realloc(*cost, need * sizeof *nb);
  if (!nb) return nomem(err);
  *cost = nb;
  *cap = need;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* (1) Frames */

typedef struct {
  int64_t f_min;
  int n;             /* frames f_min .. f_min + n - 1 */
  double *t_us;      /* n; NaN where unknown (outside known frames: none) */
} frames_t;

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

static elfm_status frames_build(frames_t *fr, const elfm_table *dets, const int *cd,
                                const elfm_table *trk, const int *ct, int64_t n_frames_hint,
                                elfm_error *err)
{
  int64_t fmin = INT64_MAX, fmax = INT64_MIN;
  elfm_status s;
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
    return nomem(err);
  }
  for (int i = 0; i < fr->n; i++) fr->t_us[i] = NAN;
  s = ELFM_OK;
  if (dets) s = frames_fill(fr, dets, cd[0], cd[1], src_row, src_tab, err);
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

/* ---------------------------------------------------------------------- */
/* Points at frame slots: the truth samples that count, the detections, the
 * candidate tracks' real points. */

typedef struct {
  int64_t n;         /* points */
  int *frame;        /* frame slot (0..n_frames-1) */
  double *x, *y, *z; /* um */
} points_t;

static void points_free(points_t *p)
{
  free(p->frame);
  free(p->x);
  free(p->y);
  free(p->z);
}

/* Room for cap points (at least 1), contents kept. On failure the arrays
 * that did grow stay in p, so points_free still frees everything. */
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
  if (!f || !x || !y || !z) return nomem(err);
  return ELFM_OK;
}

/* Points grouped per frame slot and sorted by x within a frame, for gated
 * look-ups: entries [off[f], off[f+1]) of *by_x are {x, point index} of
 * frame f. off has n_frames + 1 entries, by_x p->n (+1); the caller frees
 * both. */
static elfm_status index_by_frame(const points_t *p, int n_frames, int64_t **off_out,
                                  keyed_t **by_x_out, elfm_error *err)
{
  int64_t *off = calloc((size_t)n_frames + 1, sizeof *off);
  keyed_t *by_x = malloc(((size_t)p->n + 1) * sizeof *by_x);
  int64_t *fill = malloc(((size_t)n_frames + 1) * sizeof *fill);
  if (!off || !by_x || !fill) {
    free(off);
    free(by_x);
    free(fill);
    return nomem(err);
  }
  for (int64_t i = 0; i < p->n; i++) off[p->frame[i] + 1]++;
  for (int f = 0; f < n_frames; f++) off[f + 1] += off[f];
  memcpy(fill, off, ((size_t)n_frames + 1) * sizeof *fill);
  for (int64_t i = 0; i < p->n; i++) by_x[fill[p->frame[i]]++] = (keyed_t){p->x[i], (size_t)i};
  free(fill);
  for (int f = 0; f < n_frames; f++)
    qsort(by_x + off[f], (size_t)(off[f + 1] - off[f]), sizeof *by_x, keyed_cmp);
  *off_out = off;
  *by_x_out = by_x;
  return ELFM_OK;
}

/* First position in by_x[a..b) whose x is >= x0. */
static int64_t lower_x(const keyed_t *by_x, int64_t a, int64_t b, double x0)
{
  while (a < b) {
    int64_t mid = a + (b - a) / 2;
    if (by_x[mid].key < x0) a = mid + 1;
    else b = mid;
  }
  return a;
}

/* ---------------------------------------------------------------------- */
/* (2) Truth at the frames */

typedef struct {
  int n_obj;
  /* the points that count; those of object k are [obj_off[k], obj_off[k+1])
   * in frame order */
  points_t pt;
  int64_t *obj_off;
  /* per frame slot f: fr_pt[fr_off[f] .. fr_off[f+1]) = {x, point index},
   * sorted by x (index_by_frame) */
  int64_t *fr_off;
  keyed_t *fr_pt;
} truth_t;

static void truth_free(truth_t *t)
{
  points_free(&t->pt);
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

static elfm_status truth_build(truth_t *tr, const elfm_table *tt, const frames_t *fr,
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
  size_t bad;
  if ((s = group_rows(tt, c[0], c[1], &ord, &bad, err)) != ELFM_OK) return s;
  if (bad < n) {
    double t0 = elfm_table_get(tt, ord[bad - 1].idx, c[1]), t1 = elfm_table_get(tt, ord[bad].idx, c[1]);
    elfm_error_set_line(err, ELFM_ERR_FORMAT, tt->path, tt->line[ord[bad].idx],
                        "truth for id %.0f is not sorted by time: t_us %.0f follows %.0f "
                        "(line %lld)",
                        ord[bad].key, t1, t0, (long long)tt->line[ord[bad - 1].idx]);
    free(ord);
    return ELFM_ERR_FORMAT;
  }
  int n_obj = 0;
  for (size_t i = 0; i < n; i++) n_obj += (i == 0 || ord[i].key != ord[i - 1].key);
  tr->n_obj = n_obj;
  tr->obj_off = malloc(((size_t)n_obj + 1) * sizeof *tr->obj_off);
  if (!tr->obj_off) { free(ord); return nomem(err); }
  int64_t cap = 0;
  size_t i = 0;
  int k = 0;
  s = ELFM_OK;
  while (i < n && s == ELFM_OK) {
    size_t j = i;
    while (j < n && ord[j].key == ord[i].key) j++;
    tr->obj_off[k] = tr->pt.n;
    /* Samples ord[i..j) of this object, increasing t. Walk the frames that
     * fall inside its time range with one cursor. */
    double t_first = elfm_table_get(tt, ord[i].idx, c[1]);
    double t_last = elfm_table_get(tt, ord[j - 1].idx, c[1]);
    size_t cur = i, wcur = i;
    for (int f = 0; f < fr->n && s == ELFM_OK; f++) {
      double t = fr->t_us[f];
      if (!(t >= t_first && t <= t_last)) continue; /* also skips unknown (NaN) times */
      while (cur + 1 < j && elfm_table_get(tt, ord[cur + 1].idx, c[1]) < t) cur++;
      /* Window rule (elfm_score.h, window_us): bright for at least half of
       * the samples in (t - window, t]; samples are dense (<= 100 us, SPEC
       * §6). With no sample inside the window, the value at t decides. */
      int window_votes = -1; /* -1: no vote, 0 dark, 1 lit */
      if (o->window_us > 0) {
        while (wcur < j && elfm_table_get(tt, ord[wcur].idx, c[1]) <= t - o->window_us) wcur++;
        int64_t n_in = 0, n_lit = 0;
        for (size_t q = wcur; q < j && elfm_table_get(tt, ord[q].idx, c[1]) <= t; q++) {
          n_in++;
          n_lit += elfm_table_get(tt, ord[q].idx, c[5]) > 0;
        }
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
      if (!lit || !inside(o, val[0], val[1], val[2])) continue;
      if (tr->pt.n == cap) {
        cap = cap ? 2 * cap : 1024;
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
  return index_by_frame(&tr->pt, fr->n, &tr->fr_off, &tr->fr_pt, err);
}

/* Number of truth ids with at least one sample that counts (bright, inside
 * the volume): used when the run produced no frame at all. */
static elfm_status truth_ids_seen(const elfm_table *tt, const elfm_score_options *o, int *n_ids,
                                  elfm_error *err)
{
  int c[6];
  elfm_status s = elfm_table_require(tt, truth_cols, 6, c, err);
  if (s != ELFM_OK) return s;
  double *ids = malloc((tt->n_rows + 1) * sizeof *ids);
  if (!ids) return nomem(err);
  size_t n = 0;
  for (size_t r = 0; r < tt->n_rows; r++)
    if (elfm_table_get(tt, r, c[5]) > 0 &&
        inside(o, elfm_table_get(tt, r, c[2]), elfm_table_get(tt, r, c[3]),
               elfm_table_get(tt, r, c[4])))
      ids[n++] = elfm_table_get(tt, r, c[0]);
  keyed_t *k = malloc((n + 1) * sizeof *k);
  if (!k) { free(ids); return nomem(err); }
  for (size_t i = 0; i < n; i++) k[i] = (keyed_t){ids[i], i};
  qsort(k, n, sizeof *k, keyed_cmp);
  int u = 0;
  for (size_t i = 0; i < n; i++) u += (i == 0 || k[i].key != k[i - 1].key);
  free(k);
  free(ids);
  *n_ids = u;
  return ELFM_OK;
}

/* Object of truth point p (binary search in obj_off). */
static int truth_obj_of(const truth_t *tr, int64_t p)
{
  int lo = 0, hi = tr->n_obj - 1;
  while (lo < hi) {
    int mid = (lo + hi + 1) / 2;
    if (tr->obj_off[mid] <= p) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

/* Number of visible frames of object k within frame slots [f0, f1]. */
/* 1 if truth object k counts at frame slot f (its points are in frame order). */
static int truth_has(const truth_t *tr, int k, int f)
{
  int64_t lo = tr->obj_off[k], hi = tr->obj_off[k + 1];
  while (lo < hi) {
    int64_t m = lo + (hi - lo) / 2;
    if (tr->pt.frame[m] < f) lo = m + 1;
    else hi = m;
  }
  return lo < tr->obj_off[k + 1] && tr->pt.frame[lo] == f;
}

/* ---------------------------------------------------------------------- */
/* (3) Detections per frame */

static elfm_status score_detections(const truth_t *tr, const frames_t *fr, const points_t *dp,
                                    const gate_t *g, elfm_score_result *out, elfm_error *err)
{
  /* Group detections per frame, sorted by x. */
  int64_t *off;
  keyed_t *ds;
  elfm_status s = index_by_frame(dp, fr->n, &off, &ds, err);
  if (s != ELFM_OK) return s;
  int max_t = 0, max_d = 0;
  for (int f = 0; f < fr->n; f++) {
    int nt = (int)(tr->fr_off[f + 1] - tr->fr_off[f]), nd = (int)(off[f + 1] - off[f]);
    if (nt > max_t) max_t = nt;
    if (nd > max_d) max_d = nd;
  }
  /* Scratch sized once for the largest frame (nothing allocated per frame). */
  size_t nn = (size_t)max_t + (size_t)max_d + 1;
  int *parent = malloc(nn * sizeof *parent);
  int *head = malloc(nn * sizeof *head);   /* first node of each root's chain, or -1 */
  int *next = malloc(nn * sizeof *next);   /* next node in the same component, or -1 */
  int *rows = malloc(nn * sizeof *rows), *cols = malloc(nn * sizeof *cols);
  int *r2c = malloc(nn * sizeof *r2c);
  double *cost = NULL;
  size_t cost_cap = 0;
  elfm_assign_workspace *ws = NULL;
  if (!parent || !head || !next || !rows || !cols || !r2c) { s = nomem(err); goto done; }
  if ((s = elfm_assign_workspace_create(0, 0, &ws, err)) != ELFM_OK) goto done;

  int64_t tp = 0;
  double sx = 0, sy = 0, sz = 0;
  for (int f = 0; f < fr->n; f++) {
    int64_t ta = tr->fr_off[f];
    int nt = (int)(tr->fr_off[f + 1] - ta);
    int64_t da = off[f];
    int nd = (int)(off[f + 1] - da);
    if (nt == 0 || nd == 0) continue;
    for (int q = 0; q < nt + nd; q++) parent[q] = q;
    /* Edges d < eps: for each truth point, detections with |dx| < eps. */
    int any = 0;
    for (int i = 0; i < nt; i++) {
      int64_t p = (int64_t)tr->fr_pt[ta + i].idx;
      int lo = (int)(lower_x(ds, da, da + nd, tr->pt.x[p] - g->eps) - da);
      for (int j = lo; j < nd && ds[da + j].key < tr->pt.x[p] + g->eps; j++) {
        int di = (int)ds[da + j].idx;
        if (dist_aniso(g, dp->x[di] - tr->pt.x[p], dp->y[di] - tr->pt.y[p], dp->z[di] - tr->pt.z[p]) < g->eps) {
          uf_union(parent, i, nt + j);
          any = 1;
        }
      }
    }
    if (!any) continue;
    /* Solve each connected component with >= 2 nodes. Nodes are chained
     * per root (linear time; scanning all nodes per root was quadratic). */
    for (int q = 0; q < nt + nd; q++) head[q] = -1;
    for (int q = nt + nd - 1; q >= 0; q--) {
      int root = uf_find(parent, q);
      next[q] = head[root];
      head[root] = q;
    }
    for (int root = 0; root < nt + nd; root++) {
      if (head[root] < 0 || next[head[root]] < 0) continue;
      int nr = 0, nc = 0;
      for (int q = head[root]; q >= 0; q = next[q]) {
        if (q < nt) rows[nr++] = q;
        else cols[nc++] = q - nt;
      }
      if (nr == 0 || nc == 0) continue;
      size_t need = (size_t)nr * (size_t)nc;
      if ((s = reserve_cost(&cost, &cost_cap, need, err)) != ELFM_OK) goto done;
      for (int a = 0; a < nr; a++) {
        int64_t p = (int64_t)tr->fr_pt[ta + rows[a]].idx;
        for (int b = 0; b < nc; b++) {
          int di = (int)ds[da + cols[b]].idx;
          double d = dist_aniso(g, dp->x[di] - tr->pt.x[p], dp->y[di] - tr->pt.y[p], dp->z[di] - tr->pt.z[p]);
          cost[(size_t)a * (size_t)nc + (size_t)b] = d < g->eps ? d : INFINITY;
        }
      }
      if ((s = elfm_assign_hungarian(cost, nr, nc, r2c, NULL, ws, err)) != ELFM_OK) goto done;
      for (int a = 0; a < nr; a++) {
        if (r2c[a] < 0) continue;
        int64_t p = (int64_t)tr->fr_pt[ta + rows[a]].idx;
        int di = (int)ds[da + cols[r2c[a]]].idx;
        double dx = dp->x[di] - tr->pt.x[p], dy = dp->y[di] - tr->pt.y[p], dz = dp->z[di] - tr->pt.z[p];
        tp++;
        sx += dx * dx;
        sy += dy * dy;
        sz += dz * dz;
      }
    }
  }
  out->n_truth_points = tr->pt.n;
  out->n_detections = dp->n;
  out->n_true_positives = tp;
  out->recall = tr->pt.n ? (double)tp / (double)tr->pt.n : NAN;
  out->precision = dp->n ? (double)tp / (double)dp->n : NAN;
  out->f1 = (tr->pt.n + dp->n) ? 2.0 * (double)tp / (double)(tr->pt.n + dp->n) : NAN;
  out->rmse_x_um = tp ? sqrt(sx / (double)tp) : NAN;
  out->rmse_y_um = tp ? sqrt(sy / (double)tp) : NAN;
  out->rmse_z_um = tp ? sqrt(sz / (double)tp) : NAN;
done:
  elfm_assign_workspace_free(ws);
  free(cost);
  free(parent);
  free(head);
  free(next);
  free(rows);
  free(cols);
  free(r2c);
  free(off);
  free(ds);
  return s;
}

/* ---------------------------------------------------------------------- */
/* (4) Tracks */

typedef struct {
  int n_tracks;
  int *off;    /* real points of track c: pt [off[c], off[c+1]) in frame order */
  points_t pt; /* smoothed positions */
} cands_t;

static void cands_free(cands_t *c)
{
  free(c->off);
  points_free(&c->pt);
}

/* Columns: 0 track_id 1 frame 2 t_us 3 x 4 y 5 z 6 raw_x 7 raw_y 8 raw_z */
static elfm_status cands_build(cands_t *cd, points_t *raw, const elfm_table *t, const int *c,
                               const frames_t *fr, elfm_error *err)
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
  size_t bad;
  if ((s = group_rows(t, c[0], c[1], &ord, &bad, err)) != ELFM_OK) return s;
  if (bad < n) {
    double f0 = elfm_table_get(t, ord[bad - 1].idx, c[1]), f1 = elfm_table_get(t, ord[bad].idx, c[1]);
    elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[ord[bad].idx],
                        "track %.0f: frame %.0f follows frame %.0f (line %lld); a track's "
                        "rows must be in increasing frame order, one per frame",
                        ord[bad].key, f1, f0, (long long)t->line[ord[bad - 1].idx]);
    free(ord);
    return ELFM_ERR_FORMAT;
  }
  int n_tracks = 0;
  /* Count tracks with at least one real point. */
  for (size_t i = 0; i < n;) {
    size_t j = i;
    int real = 0;
    while (j < n && ord[j].key == ord[i].key) real |= isfinite(elfm_table_get(t, ord[j++].idx, c[6]));
    n_tracks += real;
    i = j;
  }
  cd->n_tracks = n_tracks;
  cd->off = malloc(((size_t)n_tracks + 1) * sizeof *cd->off);
  if (!cd->off) { free(ord); return nomem(err); }
  if ((s = points_reserve(&cd->pt, n, err)) != ELFM_OK ||
      (raw && (s = points_reserve(raw, n, err)) != ELFM_OK)) { free(ord); return s; }
  int k = 0, np = 0;
  for (size_t i = 0; i < n;) {
    size_t j = i;
    int start = np;
    while (j < n && ord[j].key == ord[i].key) {
      size_t r = ord[j++].idx;
      if (!isfinite(elfm_table_get(t, r, c[6]))) continue;
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

typedef struct {
  int obj, cand;
  int64_t matched;
  double saving;   /* sum over matched frames of (eps - d) */
  double sum_d2;
  double cost;     /* d(X, Y) */
} pair_t;

static elfm_status score_tracks(const truth_t *tr, const cands_t *cd, const gate_t *g,
                                elfm_score_result *out, elfm_error *err)
{
  elfm_status s = ELFM_OK;
  int n_obj = tr->n_obj, n_c = cd->n_tracks;
  /* Truth tracks: objects with at least one counted point. */
  int n_truth_tracks = 0;
  for (int k = 0; k < n_obj; k++) n_truth_tracks += tr->obj_off[k + 1] > tr->obj_off[k];

  pair_t *pairs = NULL;
  size_t n_pairs = 0, cap_pairs = 0;
  int64_t *acc_m = calloc((size_t)n_obj + 1, sizeof *acc_m);
  double *acc_s = calloc((size_t)n_obj + 1, sizeof *acc_s);
  double *acc_d2 = calloc((size_t)n_obj + 1, sizeof *acc_d2);
  int *touched = malloc(((size_t)n_obj + 1) * sizeof *touched);
  int *parent = malloc(((size_t)n_obj + (size_t)n_c + 1) * sizeof *parent);
  int *obj_pair = malloc(((size_t)n_obj + 1) * sizeof *obj_pair);  /* chosen pair, -1 dummy */
  unsigned char *cand_used = calloc((size_t)n_c + 1, 1);
  int *rows = malloc(((size_t)n_obj + 1) * sizeof *rows);
  int *cols = malloc(((size_t)n_c + 1) * sizeof *cols);
  int *col_of = malloc(((size_t)n_c + 1) * sizeof *col_of);
  int *r2c = malloc(((size_t)n_obj + 1) * sizeof *r2c);
  double *cost = NULL;
  size_t cost_cap = 0;
  elfm_assign_workspace *ws = NULL;
  if (!acc_m || !acc_s || !acc_d2 || !touched || !parent || !obj_pair || !cand_used || !rows ||
      !cols || !col_of || !r2c) { s = nomem(err); goto done; }

  /* Gated matches of every candidate with every truth object. */
  for (int ci = 0; ci < n_c; ci++) {
    int n_touched = 0;
    int a = cd->off[ci], b = cd->off[ci + 1];
    for (int q = a; q < b; q++) {
      int f = cd->pt.frame[q];
      int64_t fa = tr->fr_off[f], fb = tr->fr_off[f + 1];
      for (int64_t m = lower_x(tr->fr_pt, fa, fb, cd->pt.x[q] - g->eps);
           m < fb && tr->fr_pt[m].key < cd->pt.x[q] + g->eps; m++) {
        int64_t p = (int64_t)tr->fr_pt[m].idx;
        double d = dist_aniso(g, cd->pt.x[q] - tr->pt.x[p], cd->pt.y[q] - tr->pt.y[p], cd->pt.z[q] - tr->pt.z[p]);
        if (!(d < g->eps)) continue;
        int k = truth_obj_of(tr, p);
        if (acc_m[k] == 0) touched[n_touched++] = k;
        acc_m[k]++;
        acc_s[k] += g->eps - d;
        acc_d2[k] += d * d;
      }
    }
    int n_real = b - a;
    for (int t = 0; t < n_touched; t++) {
      int k = touched[t];
      int64_t fx = tr->obj_off[k + 1] - tr->obj_off[k];
      /* |F(X) u R(Y)| = |F(X)| + |R(Y)| - |F(X) n R(Y)| (see elfm_score.h) */
      int64_t both = 0;
      for (int q = a; q < b; q++) both += truth_has(tr, k, cd->pt.frame[q]);
      if (n_pairs == cap_pairs) {
        size_t nc = cap_pairs ? 2 * cap_pairs : 256;
        pair_t *np = realloc(pairs, nc * sizeof *np);
        if (!np) { s = nomem(err); goto done; }
        pairs = np;
        cap_pairs = nc;
      }
      pair_t *pp = &pairs[n_pairs++];
      pp->obj = k;
      pp->cand = ci;
      pp->matched = acc_m[k];
      pp->saving = acc_s[k];
      pp->sum_d2 = acc_d2[k];
      pp->cost = g->eps * (double)(fx + n_real - both) - acc_s[k];
      acc_m[k] = 0;
      acc_s[k] = 0;
      acc_d2[k] = 0;
    }
  }

  /* Clusters: truth objects and candidates joined by feasible pairs. */
  for (int q = 0; q < n_obj + n_c; q++) parent[q] = q;
  for (size_t q = 0; q < n_pairs; q++) uf_union(parent, pairs[q].obj, n_obj + pairs[q].cand);
  for (int k = 0; k < n_obj; k++) obj_pair[k] = -1;
  /* Pairs grouped by root: order pairs by root of their object. */
  {
    keyed_t *po = malloc((n_pairs + 1) * sizeof *po);
    pair_t *sorted = malloc((n_pairs + 1) * sizeof *sorted);
    if (!po || !sorted) { free(po); free(sorted); s = nomem(err); goto done; }
    for (size_t q = 0; q < n_pairs; q++) po[q] = (keyed_t){(double)uf_find(parent, pairs[q].obj), q};
    qsort(po, n_pairs, sizeof *po, keyed_cmp);
    for (size_t q = 0; q < n_pairs; q++) sorted[q] = pairs[po[q].idx];
    free(po);
    free(pairs);
    pairs = sorted;
  }
  if ((s = elfm_assign_workspace_create(0, 0, &ws, err)) != ELFM_OK) goto done;
  for (size_t q0 = 0; q0 < n_pairs;) {
    int root = uf_find(parent, pairs[q0].obj);
    size_t q1 = q0;
    while (q1 < n_pairs && uf_find(parent, pairs[q1].obj) == root) q1++;
    /* Rows: objects of the cluster; columns: its candidates, then one
     * dummy per object (only its own dummy is allowed). */
    int nr = 0, nc = 0;
    for (size_t q = q0; q < q1; q++) {
      int k = pairs[q].obj, c = pairs[q].cand;
      if (obj_pair[k] != -2) { obj_pair[k] = -2; rows[nr++] = k; }
      if (!cand_used[c]) { cand_used[c] = 1; col_of[c] = nc; cols[nc++] = c; }
    }
    for (int c = 0; c < nc; c++) cand_used[cols[c]] = 0;
    int ncol = nc + nr;
    size_t need = (size_t)nr * (size_t)ncol;
    if ((s = reserve_cost(&cost, &cost_cap, need, err)) != ELFM_OK) goto done;
    for (size_t e = 0; e < need; e++) cost[e] = INFINITY;
    for (int r = 0; r < nr; r++) {
      int k = rows[r];
      obj_pair[k] = r; /* temporarily: row index of object k */
      cost[(size_t)r * (size_t)ncol + (size_t)(nc + r)] =
          g->eps * (double)(tr->obj_off[k + 1] - tr->obj_off[k]);
    }
    for (size_t q = q0; q < q1; q++)
      cost[(size_t)obj_pair[pairs[q].obj] * (size_t)ncol + (size_t)col_of[pairs[q].cand]] = pairs[q].cost;
    if ((s = elfm_assign_hungarian(cost, nr, ncol, r2c, NULL, ws, err)) != ELFM_OK) goto done;
    /* obj_pair[k] still holds k's row here; turn it into the chosen pair. */
    for (size_t q = q0; q < q1; q++) {
      int k = pairs[q].obj;
      if (obj_pair[k] < 0) continue; /* already resolved */
      int c = r2c[obj_pair[k]];
      if (c >= 0 && c < nc && cols[c] == pairs[q].cand) obj_pair[k] = -3 - (int)q;
    }
    for (int r = 0; r < nr; r++) {
      int k = rows[r];
      obj_pair[k] = obj_pair[k] <= -3 ? -3 - obj_pair[k] : -1;
    }
    q0 = q1;
  }

  /* Measures. */
  {
    double d_empty = 0, d_pairs = 0, d_spur = 0, sum_d2 = 0;
    int64_t tp = 0, fn = 0, fp = 0;
    int paired = 0, missed = 0, spurious = 0;
    memset(cand_used, 0, (size_t)n_c + 1);
    for (int k = 0; k < n_obj; k++) {
      int64_t fx = tr->obj_off[k + 1] - tr->obj_off[k];
      if (fx == 0) continue;
      d_empty += g->eps * (double)fx;
      if (obj_pair[k] >= 0) {
        const pair_t *pp = &pairs[obj_pair[k]];
        d_pairs += pp->cost;
        tp += pp->matched;
        fn += fx - pp->matched;
        fp += (cd->off[pp->cand + 1] - cd->off[pp->cand]) - pp->matched;
        sum_d2 += pp->sum_d2;
        cand_used[pp->cand] = 1;
        paired++;
      } else {
        d_pairs += g->eps * (double)fx;
        fn += fx;
        missed++;
      }
    }
    for (int c = 0; c < n_c; c++) {
      if (cand_used[c]) continue;
      int a = cd->off[c], b = cd->off[c + 1];
      d_spur += g->eps * (double)(b - a);
      fp += b - a;
      spurious++;
    }
    out->has_tracks = 1;
    out->n_truth_tracks = n_truth_tracks;
    out->n_candidate_tracks = n_c;
    out->n_paired_tracks = paired;
    out->n_missed_tracks = missed;
    out->n_spurious_tracks = spurious;
    out->n_track_tp = tp;
    out->n_track_fn = fn;
    out->n_track_fp = fp;
    out->alpha = d_empty > 0 ? 1.0 - d_pairs / d_empty : NAN;
    out->beta = d_empty + d_spur > 0 ? (d_empty - d_pairs) / (d_empty + d_spur) : NAN;
    out->jaccard_tracks = paired + missed + spurious
                              ? (double)paired / (double)(paired + missed + spurious) : NAN;
    out->jaccard_detections = tp + fn + fp ? (double)tp / (double)(tp + fn + fp) : NAN;
    out->rmse_tracks_um = tp ? sqrt(sum_d2 / (double)tp) : NAN;
  }
done:
  elfm_assign_workspace_free(ws);
  free(pairs);
  free(cost);
  free(acc_m);
  free(acc_s);
  free(acc_d2);
  free(touched);
  free(parent);
  free(obj_pair);
  free(cand_used);
  free(rows);
  free(cols);
  free(col_of);
  free(r2c);
  return s;
}

/* ---------------------------------------------------------------------- */
/* (5) Stage velocity */

static void score_stage(const elfm_table *t, const int *c, const elfm_score_options *o,
                        elfm_score_result *out)
{
  const char *vn[3] = {"vx_um_per_ms", "vy_um_per_ms", "vz_um_per_ms"};
  int cv[3];
  int have_v = 1;
  for (int a = 0; a < 3; a++) have_v &= (cv[a] = elfm_table_col(t, vn[a])) >= 0;
  double sum[3] = {0, 0, 0};
  int64_t n = 0;
  if (have_v) {
    for (size_t r = 0; r < t->n_rows; r++) {
      if (!isfinite(elfm_table_get(t, r, c[6]))) continue;
      double v[3];
      int ok = 1;
      for (int a = 0; a < 3; a++) ok &= isfinite(v[a] = elfm_table_get(t, r, cv[a]));
      if (!ok) continue;
      for (int a = 0; a < 3; a++) sum[a] += v[a];
      n++;
    }
  } else {
    /* Per track: displacement of the first to the last real row over time,
     * assuming rows of a track are in frame order (checked earlier). */
    for (size_t r = 0; r < t->n_rows; r++) {
      if (!isfinite(elfm_table_get(t, r, c[6]))) continue;
      double id = elfm_table_get(t, r, c[0]);
      int first = 1;
      for (size_t q = 0; q < r; q++)
        if (elfm_table_get(t, q, c[0]) == id && isfinite(elfm_table_get(t, q, c[6]))) { first = 0; break; }
      if (!first) continue;
      size_t last = r;
      for (size_t q = r + 1; q < t->n_rows; q++)
        if (elfm_table_get(t, q, c[0]) == id && isfinite(elfm_table_get(t, q, c[6]))) last = q;
      double dt_ms = (elfm_table_get(t, last, c[2]) - elfm_table_get(t, r, c[2])) / 1000.0;
      if (!(dt_ms > 0)) continue;
      for (int a = 0; a < 3; a++)
        sum[a] += (elfm_table_get(t, last, c[3 + a]) - elfm_table_get(t, r, c[3 + a])) / dt_ms;
      n++;
    }
  }
  if (n == 0) return;
  double e2 = 0, s2 = 0;
  for (int a = 0; a < 3; a++) {
    out->mean_v_um_per_ms[a] = sum[a] / (double)n;
    double d = out->mean_v_um_per_ms[a] - o->stage_v_um_per_ms[a];
    e2 += d * d;
    s2 += o->stage_v_um_per_ms[a] * o->stage_v_um_per_ms[a];
  }
  out->has_stage = 1;
  out->stage_rel_error = s2 > 0 ? sqrt(e2 / s2) : NAN;
}

/* ---------------------------------------------------------------------- */

elfm_status elfm_score_tables(const elfm_table *truth, const elfm_table *tracks,
                              const elfm_table *detections, const elfm_score_options *opt,
                              elfm_score_result *out, elfm_error *err)
{
  memset(out, 0, sizeof *out);
  out->recall = out->precision = out->f1 = NAN;
  out->rmse_x_um = out->rmse_y_um = out->rmse_z_um = NAN;
  out->alpha = out->beta = out->jaccard_tracks = out->jaccard_detections = NAN;
  out->rmse_tracks_um = out->stage_rel_error = NAN;
  if (!truth || (!tracks && !detections) || !opt)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "scoring needs truth and tracks or detections");
  if (!(opt->eps_um > 0) || !(opt->kz > 0) || !isfinite(opt->eps_um) || !isfinite(opt->kz))
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "gate eps %g um and kz %g must be positive", opt->eps_um, opt->kz);
  gate_t g = {opt->eps_um, opt->kz};

  int cd[5], ct[9];
  elfm_status s;
  if (detections && (s = elfm_table_require(detections, det_cols, 5, cd, err)) != ELFM_OK) return s;
  if (tracks && (s = elfm_table_require(tracks, track_cols, 9, ct, err)) != ELFM_OK) return s;

  frames_t fr = {0, 0, NULL};
  truth_t tr;
  memset(&tr, 0, sizeof tr);
  points_t dp, raw;
  memset(&dp, 0, sizeof dp);
  memset(&raw, 0, sizeof raw);
  cands_t cand;
  memset(&cand, 0, sizeof cand);

  if ((s = frames_build(&fr, detections, cd, tracks, ct, opt->n_frames_hint, err)) != ELFM_OK)
    goto done;
  out->n_frames = fr.n;
  if ((s = truth_build(&tr, truth, &fr, opt, err)) != ELFM_OK) goto done;

  if (detections) {
    if ((s = points_reserve(&dp, detections->n_rows, err)) != ELFM_OK) goto done;
    for (size_t r = 0; r < detections->n_rows; r++) {
      double v[3] = {0, 0, 0};
      for (int a = 0; a < 3; a++)
        if ((s = get_req(detections, r, cd[2 + a], det_cols[2 + a], &v[a], err)) != ELFM_OK) goto done;
      dp.frame[dp.n] = (int)((int64_t)elfm_table_get(detections, r, cd[0]) - fr.f_min);
      dp.x[dp.n] = v[0];
      dp.y[dp.n] = v[1];
      dp.z[dp.n] = v[2];
      dp.n++;
    }
  }
  if (tracks) {
    if ((s = cands_build(&cand, detections ? NULL : &raw, tracks, ct, &fr, err)) != ELFM_OK) goto done;
  }
  out->detections_from_tracks = detections ? 0 : 1;
  if ((s = score_detections(&tr, &fr, detections ? &dp : &raw, &g, out, err)) != ELFM_OK) goto done;
  if (tracks) {
    if ((s = score_tracks(&tr, &cand, &g, out, err)) != ELFM_OK) goto done;
    if (opt->have_stage) score_stage(tracks, ct, opt, out);
  }
  if (fr.n == 0) {
    /* No detection and no track point at all: there is no frame list to
     * sample the truth at, but if the truth shows any object the run missed
     * everything: recall, F1, alpha, beta and the Jaccards are 0 (precision
     * stays undefined). */
    int seen = 0;
    if ((s = truth_ids_seen(truth, opt, &seen, err)) != ELFM_OK) goto done;
    if (seen > 0) {
      out->recall = out->f1 = 0.0;
      if (tracks) {
        out->alpha = out->beta = out->jaccard_tracks = out->jaccard_detections = 0.0;
        out->n_truth_tracks = out->n_missed_tracks = seen;
      }
    }
  }
done:
  free(fr.t_us);
  truth_free(&tr);
  points_free(&dp);
  points_free(&raw);
  cands_free(&cand);
  return s;
}

elfm_status elfm_score_files(const char *truth_csv, const char *tracks_csv,
                             const char *detections_csv, const elfm_score_options *opt,
                             elfm_score_result *out, elfm_error *err)
{
  elfm_table *truth = NULL, *tracks = NULL, *dets = NULL;
  elfm_status s = elfm_table_load_csv(truth_csv, &truth, err);
  if (s == ELFM_OK && tracks_csv) s = elfm_table_load_csv(tracks_csv, &tracks, err);
  if (s == ELFM_OK && detections_csv) s = elfm_table_load_csv(detections_csv, &dets, err);
  if (s == ELFM_OK) s = elfm_score_tables(truth, tracks, dets, opt, out, err);
  elfm_table_free(truth);
  elfm_table_free(tracks);
  elfm_table_free(dets);
  return s;
}
