/* traces.c — intensity traces per object (see elfm_traces.h). */
#include "elfm_traces.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One point of an object: a track's row, or a clustered detection. */
typedef struct trace_point {
  int64_t t_us;
  double x_um, y_um, z_um;
  int detected;
} trace_point;

typedef struct trace_object {
  int64_t id;
  size_t first, n;  /* its points: pts[first .. first + n), in time order */
  size_t cursor;    /* the last point at or before the previous frame's time */
  int hold;         /* present at every time, at its end points outside them */
  size_t n_detected;
  double mean[3];
} trace_object;

struct elfm_trace_objects {
  trace_point *pts;
  trace_object *obj;
  size_t n_obj;
};

size_t elfm_trace_objects_count(const elfm_trace_objects *o) { return o ? o->n_obj : 0; }

void elfm_trace_objects_free(elfm_trace_objects *o)
{
  if (!o) return;
  free(o->pts);
  free(o->obj);
  free(o);
}

void elfm_trace_objects_info(const elfm_trace_objects *o, size_t i, elfm_trace_object_info *info)
{
  const trace_object *b = &o->obj[i];
  info->id = b->id;
  info->x_um = b->mean[0];
  info->y_um = b->mean[1];
  info->z_um = b->mean[2];
  info->n_points = b->n;
  info->n_detected = b->n_detected;
  info->first_t_us = o->pts[b->first].t_us;
  info->last_t_us = o->pts[b->first + b->n - 1].t_us;
}

static void object_summary(elfm_trace_objects *o, trace_object *b)
{
  double s[3] = {0, 0, 0};
  b->n_detected = 0;
  for (size_t k = b->first; k < b->first + b->n; k++) {
    s[0] += o->pts[k].x_um;
    s[1] += o->pts[k].y_um;
    s[2] += o->pts[k].z_um;
    b->n_detected += (size_t)o->pts[k].detected;
  }
  for (int a = 0; a < 3; a++) b->mean[a] = s[a] / (double)b->n;
  b->cursor = b->first;
}

static elfm_trace_objects *objects_alloc(size_t n_pts, size_t n_obj)
{
  elfm_trace_objects *o = calloc(1, sizeof *o);
  if (!o) return NULL;
  o->pts = malloc((n_pts ? n_pts : 1) * sizeof *o->pts);
  o->obj = calloc(n_obj ? n_obj : 1, sizeof *o->obj);
  if (!o->pts || !o->obj) {
    elfm_trace_objects_free(o);
    return NULL;
  }
  return o;
}

/* The file line of table row r (blank lines are skipped). */
static int64_t row_line(const elfm_table *t, size_t r) { return t->line ? t->line[r] : (int64_t)r + 2; }

/* Read row r's t, x, y, z (cols[0..3]) into p; 0 when one is not finite. */
static int read_point(const elfm_table *t, size_t r, const int *cols, trace_point *p)
{
  const double tu = elfm_table_get(t, r, cols[0]);
  p->x_um = elfm_table_get(t, r, cols[1]);
  p->y_um = elfm_table_get(t, r, cols[2]);
  p->z_um = elfm_table_get(t, r, cols[3]);
  if (!(fabs(tu) < 9e15) || !isfinite(p->x_um) || !isfinite(p->y_um) || !isfinite(p->z_um))
    return 0;
  p->t_us = (int64_t)llround(tu);
  return 1;
}

typedef struct row_key {
  int64_t id, t_us;
  size_t row;
} row_key;

static int cmp_row_key(const void *a, const void *b)
{
  const row_key *x = a, *y = b;
  if (x->id != y->id) return (x->id > y->id) - (x->id < y->id);
  if (x->t_us != y->t_us) return (x->t_us > y->t_us) - (x->t_us < y->t_us);
  return (x->row > y->row) - (x->row < y->row);
}

elfm_status elfm_trace_objects_from_tracks(const elfm_table *tracks, int hold,
                                           elfm_trace_objects **out, elfm_error *err)
{
  *out = NULL;
  const char *name = tracks->path;
  static const char *const need[] = {"t_us", "x_um", "y_um", "z_um", "track_id"};
  int cols[5];
  elfm_status st = elfm_table_require(tracks, need, 5, cols, err);
  if (st) return st;
  const int craw = elfm_table_col(tracks, "raw_x_um");
  const size_t n = tracks->n_rows;
  /* A long track is written in pieces (`track --piece-points`), so its rows
   * need not be together: sort by (track, time). */
  row_key *keys = malloc((n ? n : 1) * sizeof *keys);
  if (!keys) return elfm_error_set(err, ELFM_ERR_NOMEM, name, -1, "out of memory (%zu rows)", n);
  for (size_t r = 0; r < n; r++) {
    const double id = elfm_table_get(tracks, r, cols[4]), tu = elfm_table_get(tracks, r, cols[0]);
    if (!(fabs(id) < 9e15) || !(fabs(tu) < 9e15)) {
      free(keys);
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, row_line(tracks, r),
                                 "track_id and t_us must be finite numbers");
    }
    keys[r] = (row_key){(int64_t)llround(id), (int64_t)llround(tu), r};
  }
  qsort(keys, n, sizeof *keys, cmp_row_key);
  size_t n_obj = 0;
  for (size_t k = 0; k < n; k++) n_obj += k == 0 || keys[k].id != keys[k - 1].id;
  elfm_trace_objects *o = objects_alloc(n, n_obj);
  if (!o) {
    free(keys);
    return elfm_error_set(err, ELFM_ERR_NOMEM, name, -1, "out of memory (%zu rows)", n);
  }
  for (size_t k = 0; k < n; k++) {
    trace_point *p = &o->pts[k];
    if (!read_point(tracks, keys[k].row, cols, p)) {
      const int64_t line = row_line(tracks, keys[k].row);
      free(keys);
      elfm_trace_objects_free(o);
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, line,
                                 "t_us, x_um, y_um and z_um must be finite numbers");
    }
    /* without the raw columns every row counts as a detection */
    p->detected = craw < 0 || !isnan(elfm_table_get(tracks, keys[k].row, craw));
    if (k == 0 || keys[k].id != keys[k - 1].id) {
      trace_object *b = &o->obj[o->n_obj++];
      b->id = keys[k].id;
      b->first = k;
      b->hold = hold != 0;
    }
    o->obj[o->n_obj - 1].n++;
  }
  free(keys);
  for (size_t i = 0; i < o->n_obj; i++) object_summary(o, &o->obj[i]);
  *out = o;
  return ELFM_OK;
}

/* A cluster while detections are added: running sums for its mean. */
typedef struct cluster {
  double s[3];
  size_t n;
} cluster;

typedef struct det_key {
  double intensity;
  size_t row;
} det_key;

static int cmp_det_key(const void *a, const void *b)
{
  const det_key *x = a, *y = b;
  if (x->intensity != y->intensity) return (x->intensity < y->intensity) - (x->intensity > y->intensity);
  return (x->row > y->row) - (x->row < y->row);
}

typedef struct member {
  size_t cluster, row;
} member;

static int cmp_member(const void *a, const void *b)
{
  const member *x = a, *y = b;
  if (x->cluster != y->cluster) return (x->cluster > y->cluster) - (x->cluster < y->cluster);
  return (x->row > y->row) - (x->row < y->row);
}

elfm_status elfm_trace_objects_from_detections(const elfm_table *dets, double radius_um, double kz,
                                               int min_detections, elfm_trace_objects **out,
                                               elfm_error *err)
{
  *out = NULL;
  const char *name = dets->path;
  if (!(radius_um > 0) || !isfinite(radius_um) || !(kz > 0) || !isfinite(kz) || min_detections < 1)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "traces: radius and kz must be > 0, min_detections >= 1");
  static const char *const need[] = {"t_us", "x_um", "y_um", "z_um", "intensity"};
  int cols[5];
  elfm_status st = elfm_table_require(dets, need, 5, cols, err);
  if (st) return st;
  const size_t n = dets->n_rows;
  det_key *keys = malloc((n ? n : 1) * sizeof *keys);
  member *mem = malloc((n ? n : 1) * sizeof *mem);
  cluster *cl = malloc((n ? n : 1) * sizeof *cl);
  trace_point *tmp = malloc((n ? n : 1) * sizeof *tmp);
  size_t *first_row = NULL, *rank = NULL;
  elfm_trace_objects *o = NULL;
  if (!keys || !mem || !cl || !tmp) goto nomem;
  for (size_t r = 0; r < n; r++) {
    const double v = elfm_table_get(dets, r, cols[4]);
    if (!read_point(dets, r, cols, &tmp[r]) || !isfinite(v)) {
      st = elfm_error_set_line(err, ELFM_ERR_FORMAT, name, row_line(dets, r),
                               "t_us, x_um, y_um, z_um and intensity must be finite numbers");
      goto done;
    }
    tmp[r].detected = 1;
    keys[r] = (det_key){v, r};
  }
  /* Brightest first: a bright detection places its cluster best, and the
   * dim ones (a flash's tail, a defocused view) then join it. A linear scan
   * of the clusters: a static sample has tens to hundreds of objects. */
  qsort(keys, n, sizeof *keys, cmp_det_key);
  size_t nc = 0;
  const double r2 = radius_um * radius_um;
  for (size_t k = 0; k < n; k++) {
    const trace_point *p = &tmp[keys[k].row];
    size_t best = nc;
    double bd = r2;
    for (size_t c = 0; c < nc; c++) {
      const double m = 1.0 / (double)cl[c].n;
      const double dx = p->x_um - cl[c].s[0] * m, dy = p->y_um - cl[c].s[1] * m,
                   dz = (p->z_um - cl[c].s[2] * m) / kz;
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 <= bd) {
        bd = d2;
        best = c;
      }
    }
    if (best == nc) cl[nc++] = (cluster){{0, 0, 0}, 0};
    cl[best].s[0] += p->x_um;
    cl[best].s[1] += p->y_um;
    cl[best].s[2] += p->z_um;
    cl[best].n++;
    mem[k] = (member){best, keys[k].row};
  }
  /* Clusters numbered in the order of their first detection in the file
   * (detections.csv is written frame by frame), so that the objects' ids
   * do not depend on the brightness ranking; only kept clusters count. */
  first_row = malloc((nc ? nc : 1) * sizeof *first_row);
  rank = malloc((nc ? nc : 1) * sizeof *rank);
  if (!first_row || !rank) goto nomem;
  for (size_t c = 0; c < nc; c++) first_row[c] = rank[c] = (size_t)-1;
  for (size_t k = 0; k < n; k++)
    if (mem[k].row < first_row[mem[k].cluster]) first_row[mem[k].cluster] = mem[k].row;
  size_t kept = 0;
  for (size_t step = 0; step < nc; step++) {
    size_t pick = nc;
    for (size_t c = 0; c < nc; c++)
      if (rank[c] == (size_t)-1 && cl[c].n >= (size_t)min_detections &&
          (pick == nc || first_row[c] < first_row[pick]))
        pick = c;
    if (pick == nc) break;
    rank[pick] = kept++;
  }
  size_t n_keep = 0;
  for (size_t k = 0; k < n; k++)
    if (rank[mem[k].cluster] != (size_t)-1) mem[n_keep++] = (member){rank[mem[k].cluster], mem[k].row};
  qsort(mem, n_keep, sizeof *mem, cmp_member); /* by cluster, then file row */
  o = objects_alloc(n_keep, kept);
  if (!o) goto nomem;
  for (size_t k = 0; k < n_keep; k++) {
    o->pts[k] = tmp[mem[k].row];
    if (k == 0 || mem[k].cluster != mem[k - 1].cluster) {
      trace_object *b = &o->obj[o->n_obj++];
      b->id = (int64_t)mem[k].cluster;
      b->first = k;
      b->hold = 1;
    }
    o->obj[o->n_obj - 1].n++;
  }
  for (size_t i = 0; i < o->n_obj; i++) {
    trace_object *b = &o->obj[i];
    /* time order within the cluster (insertion sort: the rows were nearly in order) */
    for (size_t a = b->first + 1; a < b->first + b->n; a++) {
      trace_point v = o->pts[a];
      size_t j = a;
      while (j > b->first && o->pts[j - 1].t_us > v.t_us) {
        o->pts[j] = o->pts[j - 1];
        j--;
      }
      o->pts[j] = v;
    }
    object_summary(o, b);
    /* a static object sits at its mean, not at each detection's noise */
    for (size_t k = b->first; k < b->first + b->n; k++) {
      o->pts[k].x_um = b->mean[0];
      o->pts[k].y_um = b->mean[1];
      o->pts[k].z_um = b->mean[2];
    }
  }
  *out = o;
  o = NULL;
  st = ELFM_OK;
  goto done;
nomem:
  st = elfm_error_set(err, ELFM_ERR_NOMEM, name, -1, "out of memory (%zu rows)", n);
done:
  elfm_trace_objects_free(o);
  free(first_row);
  free(rank);
  free(keys);
  free(mem);
  free(cl);
  free(tmp);
  return st;
}

size_t elfm_trace_objects_frame(elfm_trace_objects *o, const elfm_refocus_plan *plan,
                                const elfm_frame *frame, const elfm_volume *vol,
                                elfm_trace_row *rows)
{
  const int64_t t = frame->t_us;
  /* a detection belongs to this frame within half its window */
  const int64_t half = (frame->t_end_us - frame->t_start_us) / 2;
  size_t nr = 0;
  for (size_t i = 0; i < o->n_obj; i++) {
    trace_object *b = &o->obj[i];
    const trace_point *p = o->pts + b->first;
    const size_t n = b->n;
    if (!b->hold && (t < p[0].t_us || t > p[n - 1].t_us)) continue;
    size_t c = b->cursor - b->first;
    while (c + 1 < n && p[c + 1].t_us <= t) c++;
    b->cursor = b->first + c;
    double x, y, z;
    if (t <= p[0].t_us) {
      x = p[0].x_um, y = p[0].y_um, z = p[0].z_um;
    } else if (c + 1 >= n) {
      x = p[n - 1].x_um, y = p[n - 1].y_um, z = p[n - 1].z_um;
    } else {
      const double a = (double)(t - p[c].t_us) / (double)(p[c + 1].t_us - p[c].t_us);
      x = p[c].x_um + a * (p[c + 1].x_um - p[c].x_um);
      y = p[c].y_um + a * (p[c + 1].y_um - p[c].y_um);
      z = p[c].z_um + a * (p[c + 1].z_um - p[c].z_um);
    }
    int det = 0;
    for (size_t k = c; k < n && p[k].t_us <= t + half && !det; k++)
      det = p[k].detected && p[k].t_us >= t - half;
    elfm_trace_row *r = &rows[nr++];
    r->id = b->id;
    r->x_um = x;
    r->y_um = y;
    r->z_um = z;
    r->intensity = elfm_refocus_sample(plan, frame, elfm_volume_x_vox(vol, x),
                                       elfm_volume_y_vox(vol, y), elfm_volume_z_vox(vol, z));
    r->detected = det;
  }
  return nr;
}
