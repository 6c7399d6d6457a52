/* view_data.c — what the viewer shows, read from a run directory or a CSV.
 *
 * Tracks and truth become polylines grouped by id and sorted by time (the
 * files are written frame by frame, so rows of one track are interleaved
 * with others'); detections stay points. The CSV parsing itself is the
 * tracker's table loader (elfm_table.h), which names file and line on error.
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "elfm_recon.h"
#include "elfm_gui.h"
#include "elfm_tracker.h"

typedef enum view_kind { KIND_TRACKS, KIND_TRUTH, KIND_DETECTIONS } view_kind;

static int file_exists(const char *path)
{
  struct stat st;
  return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static int dir_exists(const char *path)
{
  struct stat st;
  return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static elfm_status join_path(char *out, size_t size, const char *dir, const char *name,
                             elfm_error *err)
{
  int n = snprintf(out, size, "%s/%s", dir, name);
  if (n < 0 || (size_t)n >= size)
    return elfm_error_set(err, ELFM_ERR_INVALID, dir, -1, "path too long");
  return ELFM_OK;
}

static view_kind table_kind(const elfm_table *t)
{
  if (elfm_table_col(t, "track_id") >= 0) return KIND_TRACKS;
  if (elfm_table_col(t, "id") >= 0 && elfm_table_col(t, "brightness") >= 0) return KIND_TRUTH;
  return KIND_DETECTIONS;
}

/* Rows sorted by (id, t): qsort over row indices with the table at hand. */
typedef struct row_key {
  double id, t;
  size_t row;
} row_key;

static int row_key_cmp(const void *a, const void *b)
{
  const row_key *x = a, *y = b;
  if (x->id != y->id) return x->id < y->id ? -1 : 1;
  if (x->t != y->t) return x->t < y->t ? -1 : 1;
  return x->row < y->row ? -1 : x->row > y->row;
}

static void series_free(elfm_view_series *s)
{
  free(s->first);
  free(s->id);
  free(s->xyz_um);
  free(s->t_us);
  free(s->shared);
  memset(s, 0, sizeof *s);
}

/* Group the rows of a tracks/truth table into polylines. Rows whose
 * position is empty (NaN) are left out. */
static elfm_status series_from_table(const elfm_table *t, const char *id_name,
                                     elfm_view_series *s, elfm_error *err)
{
  const char *names[5] = {id_name, "t_us", "x_um", "y_um", "z_um"};
  int c[5];
  elfm_status st = elfm_table_require(t, names, 5, c, err);
  if (st != ELFM_OK) return st;
  row_key *keys = malloc((t->n_rows ? t->n_rows : 1) * sizeof *keys);
  if (!keys) return elfm_error_set(err, ELFM_ERR_NOMEM, t->path, -1, "out of memory");
  size_t n = 0;
  for (size_t r = 0; r < t->n_rows; r++) {
    double id = elfm_table_get(t, r, c[0]), tt = elfm_table_get(t, r, c[1]);
    double x = elfm_table_get(t, r, c[2]), y = elfm_table_get(t, r, c[3]),
           z = elfm_table_get(t, r, c[4]);
    if (isnan(id) || isnan(tt)) {
      free(keys);
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "empty %s or t_us", id_name);
    }
    if (isnan(x) || isnan(y) || isnan(z)) continue;
    keys[n].id = id;
    keys[n].t = tt;
    keys[n].row = r;
    n++;
  }
  if (n == 0) {
    free(keys);
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, 1,
                               "no rows with a position: nothing to show");
  }
  qsort(keys, n, sizeof *keys, row_key_cmp);
  size_t n_lines = 1;
  for (size_t k = 1; k < n; k++) n_lines += keys[k].id != keys[k - 1].id;
  s->first = malloc((n_lines + 1) * sizeof *s->first);
  s->id = malloc(n_lines * sizeof *s->id);
  s->xyz_um = malloc(3 * n * sizeof *s->xyz_um);
  s->t_us = malloc(n * sizeof *s->t_us);
  const int c_claims = elfm_table_col(t, "claims");
  if (c_claims >= 0) s->shared = malloc(n);
  if (!s->first || !s->id || !s->xyz_um || !s->t_us || (c_claims >= 0 && !s->shared)) {
    free(keys);
    series_free(s);
    return elfm_error_set(err, ELFM_ERR_NOMEM, t->path, -1, "out of memory");
  }
  size_t line = 0;
  for (size_t k = 0; k < n; k++) {
    size_t r = keys[k].row;
    if (k == 0 || keys[k].id != keys[k - 1].id) {
      s->first[line] = k;
      s->id[line] = (int64_t)keys[k].id;
      line++;
    }
    s->xyz_um[3 * k] = (float)elfm_table_get(t, r, c[2]);
    s->xyz_um[3 * k + 1] = (float)elfm_table_get(t, r, c[3]);
    s->xyz_um[3 * k + 2] = (float)elfm_table_get(t, r, c[4]);
    s->t_us[k] = (int64_t)llround(keys[k].t);
    /* an empty claims (a point gap filling added) is no detection: not shared */
    if (s->shared) s->shared[k] = elfm_table_get(t, r, c_claims) >= 2;
  }
  s->first[n_lines] = n;
  s->n_lines = n_lines;
  s->n_points = n;
  free(keys);
  return ELFM_OK;
}

static elfm_status detections_from_table(const elfm_table *t, elfm_view_data *d,
                                         elfm_error *err)
{
  const char *names[4] = {"t_us", "x_um", "y_um", "z_um"};
  int c[4];
  elfm_status st = elfm_table_require(t, names, 4, c, err);
  if (st != ELFM_OK) return st;
  size_t n = t->n_rows ? t->n_rows : 1;
  d->det_xyz_um = malloc(3 * n * sizeof *d->det_xyz_um);
  d->det_t_us = malloc(n * sizeof *d->det_t_us);
  if (!d->det_xyz_um || !d->det_t_us)
    return elfm_error_set(err, ELFM_ERR_NOMEM, t->path, -1, "out of memory");
  size_t k = 0;
  for (size_t r = 0; r < t->n_rows; r++) {
    double v[4];
    for (int i = 0; i < 4; i++) v[i] = elfm_table_get(t, r, c[i]);
    if (isnan(v[0]) || isnan(v[1]) || isnan(v[2]) || isnan(v[3]))
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, t->line[r],
                                 "a detection needs t_us, x_um, y_um and z_um");
    d->det_t_us[k] = (int64_t)llround(v[0]);
    for (int i = 0; i < 3; i++) d->det_xyz_um[3 * k + i] = (float)v[1 + i];
    k++;
  }
  d->n_detections = k;
  return ELFM_OK;
}

/* Frame index -> t_us, as a straight line through the table's first and
 * last frames (frames are evenly strided in a run: SPEC §5 t_us per frame). */
typedef struct frame_clock {
  int valid;
  double frame0, t0_us, us_per_frame;
} frame_clock;

static void frame_clock_from_table(const elfm_table *t, frame_clock *fc)
{
  int cf = elfm_table_col(t, "frame"), ct = elfm_table_col(t, "t_us");
  if (cf < 0 || ct < 0 || t->n_rows == 0 || fc->valid) return;
  double f_lo = INFINITY, f_hi = -INFINITY, t_lo = 0, t_hi = 0;
  for (size_t r = 0; r < t->n_rows; r++) {
    double f = elfm_table_get(t, r, cf), tt = elfm_table_get(t, r, ct);
    if (isnan(f) || isnan(tt)) continue;
    if (f < f_lo) { f_lo = f; t_lo = tt; }
    if (f > f_hi) { f_hi = f; t_hi = tt; }
  }
  if (f_hi > f_lo) {
    fc->valid = 1;
    fc->frame0 = f_lo;
    fc->t0_us = t_lo;
    fc->us_per_frame = (t_hi - t_lo) / (f_hi - f_lo);
  }
}

/* The time a MIP file stands for, from its name: "...t<digits>..." or
 * "...t_us<sep><digits>" is a time in us; otherwise the last run of digits is
 * a frame index, turned into a time with the frame clock. 0 if neither. */
static int mip_time_from_name(const char *name, const frame_clock *fc, int64_t *t_us)
{
  const char *p = strstr(name, "t_us");
  if (p) {
    p += 4;
    while (*p && (*p < '0' || *p > '9') && *p != '.') p++;
    if (*p >= '0' && *p <= '9') {
      *t_us = strtoll(p, NULL, 10);
      return 1;
    }
  }
  for (p = name; *p; p++)
    if ((*p == 't' || *p == 'T') && p[1] >= '0' && p[1] <= '9' &&
        (p == name || p[-1] == '_' || p[-1] == '-')) {
      *t_us = strtoll(p + 1, NULL, 10);
      return 1;
    }
  const char *last = NULL;
  for (p = name; *p; p++)
    if (*p >= '0' && *p <= '9' && (p == name || p[-1] < '0' || p[-1] > '9')) last = p;
  if (!last || !fc->valid) return 0;
  double f = (double)strtoll(last, NULL, 10);
  *t_us = (int64_t)llround(fc->t0_us + (f - fc->frame0) * fc->us_per_frame);
  return 1;
}

static int mip_cmp(const void *a, const void *b)
{
  const elfm_view_mip *x = a, *y = b;
  return (x->t_us > y->t_us) - (x->t_us < y->t_us);
}

/* Add every *.png (vol = 0) or *.exr (vol = 1) of `sub` whose name gives a
 * time; returns how many were added. */
static elfm_status mips_scan_dir(const char *sub, int vol, const frame_clock *fc,
                                 elfm_view_data *d, size_t *added, elfm_error *err)
{
  *added = 0;
  const char *ext = vol ? ".exr" : ".png";
  DIR *dp = opendir(sub);
  if (!dp) return ELFM_OK;
  struct dirent *e;
  size_t cap = d->n_mips;
  elfm_status st = ELFM_OK;
  while (st == ELFM_OK && (e = readdir(dp))) {
    size_t len = strlen(e->d_name);
    if (len < 5 || strcmp(e->d_name + len - 4, ext)) continue;
    int64_t t;
    if (!mip_time_from_name(e->d_name, fc, &t)) continue;
    if (d->n_mips == cap) {
      size_t nc = cap ? 2 * cap : 64;
      elfm_view_mip *m = realloc(d->mips, nc * sizeof *m);
      if (!m) {
        st = elfm_error_set(err, ELFM_ERR_NOMEM, sub, -1, "out of memory");
        break;
      }
      d->mips = m;
      cap = nc;
    }
    elfm_view_mip *m = &d->mips[d->n_mips];
    st = join_path(m->path, sizeof m->path, sub, e->d_name, err);
    if (st != ELFM_OK) break;
    m->t_us = t;
    m->is_volume = vol;
    d->n_mips++;
    (*added)++;
  }
  closedir(dp);
  if (st == ELFM_OK && d->n_mips) qsort(d->mips, d->n_mips, sizeof *d->mips, mip_cmp);
  return st;
}

/* In a run directory: MIP PNGs first (what recon made for viewing), else
 * volumes. `dir` itself may also be such a folder of pictures or volumes. */
static elfm_status mips_scan(const char *dir, const frame_clock *fc, elfm_view_data *d,
                             elfm_error *err)
{
  static const char *const subdirs[] = {"mips", "mip", "MIP", ".", "volumes", "exr", "."};
  for (size_t s = 0; s < sizeof subdirs / sizeof subdirs[0]; s++) {
    int vol = s >= 4;
    char sub[1024];
    elfm_status st = join_path(sub, sizeof sub, dir, subdirs[s], err);
    if (st != ELFM_OK) return st;
    if (!dir_exists(sub)) continue;
    size_t added = 0;
    st = mips_scan_dir(sub, vol, fc, d, &added, err);
    if (st != ELFM_OK || added) return st;
  }
  return ELFM_OK;
}

static void extent_add(double lo[3], double hi[3], const float *xyz, size_t n)
{
  for (size_t k = 0; k < n; k++)
    for (int i = 0; i < 3; i++) {
      double v = xyz[3 * k + i];
      if (v < lo[i]) lo[i] = v;
      if (v > hi[i]) hi[i] = v;
    }
}

static void time_add(int64_t *lo, int64_t *hi, const int64_t *t, size_t n)
{
  for (size_t k = 0; k < n; k++) {
    if (t[k] < *lo) *lo = t[k];
    if (t[k] > *hi) *hi = t[k];
  }
}

/* Box, time span and frame step once everything is loaded. */
static elfm_status finish_bounds(elfm_view_data *d, const frame_clock *fc, int keep_box,
                                 elfm_error *err)
{
  d->t_min_us = INT64_MAX;
  d->t_max_us = INT64_MIN;
  time_add(&d->t_min_us, &d->t_max_us, d->tracks.t_us, d->tracks.n_points);
  time_add(&d->t_min_us, &d->t_max_us, d->truth.t_us, d->truth.n_points);
  time_add(&d->t_min_us, &d->t_max_us, d->det_t_us, d->n_detections);
  if (d->t_min_us > d->t_max_us)
    return elfm_error_set(err, ELFM_ERR_FORMAT, NULL, -1, "nothing to show: no tracks, "
                          "truth or detections were loaded");
  int64_t span = d->t_max_us - d->t_min_us;
  if (fc->valid && fc->us_per_frame >= 1) d->frame_dt_us = (int64_t)llround(fc->us_per_frame);
  else d->frame_dt_us = span / 1000 > 0 ? span / 1000 : 1; /* 1000 steps across */

  if (d->box_from_calib || keep_box) return ELFM_OK;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  extent_add(lo, hi, d->tracks.xyz_um, d->tracks.n_points);
  extent_add(lo, hi, d->truth.xyz_um, d->truth.n_points);
  extent_add(lo, hi, d->det_xyz_um, d->n_detections);
  for (int i = 0; i < 3; i++) {
    /* 5 % margin, at least 1 um, so points on the extent are not on the box. */
    double m = 0.05 * (hi[i] - lo[i]);
    if (m < 1.0) m = 1.0;
    d->box_min_um[i] = lo[i] - m;
    d->box_max_um[i] = hi[i] + m;
  }
  return ELFM_OK;
}

/* The calib.json a run used, as its summary.json names it ("calib"), or "". */
static void calib_from_summary(const char *dir, char *out, size_t size)
{
  out[0] = '\0';
  char p[1024];
  if (snprintf(p, sizeof p, "%s/summary.json", dir) >= (int)sizeof p) return;
  FILE *f = fopen(p, "rb");
  if (!f) return;
  /* The whole file: summary.json lists every track (~340 bytes each), so a
   * long run's passes 1 MB, and a summary cut there is not JSON (the
   * viewer read 1 MB until the sixty-first session and lost the hint on
   * runs of ~3000 tracks). 1 GiB bounds what a hint is worth reading. */
  long bytes = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
  char *text = bytes >= 0 && bytes < (1L << 30) && fseek(f, 0, SEEK_SET) == 0
                   ? malloc((size_t)bytes + 1) : NULL;
  size_t n = text ? fread(text, 1, (size_t)bytes, f) : 0;
  fclose(f);
  if (!text) return;
  text[n] = '\0';
  cJSON *root = cJSON_Parse(text);
  free(text);
  const cJSON *c = root ? cJSON_GetObjectItemCaseSensitive(root, "calib") : NULL;
  if (cJSON_IsString(c) && c->valuestring) snprintf(out, size, "%s", c->valuestring);
  cJSON_Delete(root);
}

/* calib.json beside the data, one level up, or the one summary.json names
 * (eventlfm track keeps the calibration with the simulation or recording,
 * not in its output directory). A broken summary.json is not an error: it
 * only offers a hint. */
static elfm_status load_calib_box(const char *dir, elfm_view_data *d, elfm_error *err)
{
  char cands[3][1024];
  int n = 0;
  for (int k = 0; k < 2; k++)
    if (snprintf(cands[n], sizeof cands[n], "%s/%s", dir, k ? "../calib.json" : "calib.json") <
        (int)sizeof cands[n])
      n++;
  calib_from_summary(dir, cands[n], sizeof cands[n]);
  if (cands[n][0]) n++;
  for (int k = 0; k < n; k++) {
    const char *p = cands[k];
    if (!file_exists(p)) continue;
    elfm_calib c;
    elfm_status st = elfm_calib_load(p, &c, err);
    if (st != ELFM_OK) return st;
    /* SPEC §3: voxel X is at (X - (W-1)/2) um_per_px. */
    d->box_min_um[0] = -0.5 * (c.view_w_px - 1) * c.um_per_px;
    d->box_max_um[0] = -d->box_min_um[0];
    d->box_min_um[1] = -0.5 * (c.view_h_px - 1) * c.um_per_px;
    d->box_max_um[1] = -d->box_min_um[1];
    d->box_min_um[2] = c.z_min_um;
    d->box_max_um[2] = c.z_max_um;
    d->box_from_calib = 1;
    d->volume_w_px = c.view_w_px;
    d->volume_h_px = c.view_h_px;
    snprintf(d->calib_path, sizeof d->calib_path, "%s", p);
    return ELFM_OK;
  }
  return ELFM_OK;
}

/* Load one CSV into its place in d (by its header's kind). */
static elfm_status load_csv(const char *path, int as_truth, elfm_view_data *d,
                            frame_clock *fc, elfm_error *err)
{
  elfm_table *t = NULL;
  elfm_status st = elfm_table_load_csv(path, &t, err);
  if (st != ELFM_OK) return st;
  if (t->n_rows == 0) {
    elfm_table_free(t);
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, path, 1,
                               "header only, no rows: nothing to show");
  }
  view_kind kind = table_kind(t);
  if (as_truth && kind != KIND_TRUTH) {
    elfm_table_free(t);
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, path, 1,
                               "not a truth.csv: expected columns id,t_us,x_um,y_um,z_um,"
                               "brightness (SPEC 6)");
  }
  frame_clock_from_table(t, fc);
  if (kind == KIND_TRACKS) {
    series_free(&d->tracks);
    st = series_from_table(t, "track_id", &d->tracks, err);
  } else if (kind == KIND_TRUTH) {
    /* Alone (no tracks), truth is what is shown in colour; with tracks it
     * is the grey overlay. */
    elfm_view_series *s = (as_truth || d->tracks.n_points) ? &d->truth : &d->tracks;
    series_free(s);
    st = series_from_table(t, "id", s, err);
  } else {
    st = detections_from_table(t, d, err);
  }
  elfm_table_free(t);
  return st;
}

static void dirname_of(const char *path, char *dir, size_t size)
{
  snprintf(dir, size, "%s", path);
  char *slash = strrchr(dir, '/');
  if (!slash) snprintf(dir, size, ".");
  else if (slash == dir) dir[1] = '\0';
  else *slash = '\0';
}

elfm_status elfm_view_data_load(const char *path, const char *truth_path,
                                elfm_view_data **out, elfm_error *err)
{
  *out = NULL;
  if (!path || !*path) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no input given");
  elfm_view_data *d = calloc(1, sizeof *d);
  if (!d) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  frame_clock fc = {0};
  char dir[1024], p[1024];
  elfm_status st = ELFM_OK;

  if (dir_exists(path)) {
    snprintf(dir, sizeof dir, "%s", path);
    int found = 0;
    const char *mains[2] = {"tracks.csv", "truth.csv"};
    for (int k = 0; k < 2 && !found && st == ELFM_OK; k++) {
      st = join_path(p, sizeof p, dir, mains[k], err);
      if (st == ELFM_OK && file_exists(p)) {
        found = 1;
        st = load_csv(p, 0, d, &fc, err);
      }
    }
    if (st == ELFM_OK && !found) {
      st = join_path(p, sizeof p, dir, "detections.csv", err);
      if (st == ELFM_OK && !file_exists(p))
        st = elfm_error_set(err, ELFM_ERR_IO, path, -1,
                            "no tracks.csv, truth.csv or detections.csv in this directory");
    }
  } else if (file_exists(path)) {
    dirname_of(path, dir, sizeof dir);
    st = load_csv(path, 0, d, &fc, err);
  } else {
    st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "no such file or directory");
  }
  /* Companions beside the main file: detections, then the truth overlay. */
  if (st == ELFM_OK && d->n_detections == 0) {
    st = join_path(p, sizeof p, dir, "detections.csv", err);
    if (st == ELFM_OK && file_exists(p)) st = load_csv(p, 0, d, &fc, err);
  }
  if (st == ELFM_OK && truth_path) st = load_csv(truth_path, 1, d, &fc, err);
  if (st == ELFM_OK) st = load_calib_box(dir, d, err);
  if (st == ELFM_OK) st = mips_scan(dir, &fc, d, err);
  if (st == ELFM_OK) st = finish_bounds(d, &fc, 0, err);
  d->has_frame_clock = fc.valid;
  d->frame0 = fc.frame0;
  d->frame0_t_us = fc.t0_us;
  d->us_per_frame = fc.us_per_frame;
  if (st != ELFM_OK) {
    elfm_view_data_free(d);
    return st;
  }
  *out = d;
  return ELFM_OK;
}

elfm_status elfm_view_data_synthetic(size_t n_tracks, size_t n_points, elfm_view_data **out,
                                     elfm_error *err)
{
  *out = NULL;
  if (n_tracks == 0 || n_points < 2)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1,
                          "synthetic data needs >= 1 track of >= 2 points");
  elfm_view_data *d = calloc(1, sizeof *d);
  if (!d) return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  elfm_view_series *s = &d->tracks;
  size_t n = n_tracks * n_points;
  s->first = malloc((n_tracks + 1) * sizeof *s->first);
  s->id = malloc(n_tracks * sizeof *s->id);
  s->xyz_um = malloc(3 * n * sizeof *s->xyz_um);
  s->t_us = malloc(n * sizeof *s->t_us);
  if (!s->first || !s->id || !s->xyz_um || !s->t_us) {
    elfm_view_data_free(d);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  }
  /* A fixed linear congruential sequence (Numerical Recipes' constants): the
   * same picture on every run, no global random state. */
  uint32_t seed = 12345u;
#define SYN_RAND() ((seed = seed * 1664525u + 1013904223u) / 4294967296.0)
  for (size_t k = 0; k < n_tracks; k++) {
    s->first[k] = k * n_points;
    s->id[k] = (int64_t)k;
    double cx = -55 + 110 * SYN_RAND(), cy = -55 + 110 * SYN_RAND();
    double z0 = -90 + 180 * SYN_RAND(), r = 2 + 8 * SYN_RAND();
    double w = 2 * M_PI * (1 + 4 * SYN_RAND()) / (double)n_points;
    double vz = (SYN_RAND() - 0.5) * 60.0 / (double)n_points;
    for (size_t i = 0; i < n_points; i++) {
      size_t q = k * n_points + i;
      s->xyz_um[3 * q] = (float)(cx + r * cos(w * (double)i));
      s->xyz_um[3 * q + 1] = (float)(cy + r * sin(w * (double)i));
      s->xyz_um[3 * q + 2] = (float)(z0 + vz * (double)i);
      s->t_us[q] = (int64_t)(i * 1000); /* 1 kHz volumes */
    }
  }
#undef SYN_RAND
  s->first[n_tracks] = n;
  s->n_lines = n_tracks;
  s->n_points = n;
  d->box_min_um[0] = d->box_min_um[1] = -65;
  d->box_max_um[0] = d->box_max_um[1] = 65;
  d->box_min_um[2] = -100;
  d->box_max_um[2] = 100;
  frame_clock fc = {1, 0, 0, 1000};
  elfm_status st = finish_bounds(d, &fc, 1, err);
  if (st != ELFM_OK) {
    elfm_view_data_free(d);
    return st;
  }
  *out = d;
  return ELFM_OK;
}

elfm_status elfm_view_data_load_mips(elfm_view_data *d, const char *dir, elfm_error *err)
{
  if (!dir_exists(dir))
    return elfm_error_set(err, ELFM_ERR_IO, dir, -1, "not a directory");
  frame_clock fc = {d->has_frame_clock, d->frame0, d->frame0_t_us, d->us_per_frame};
  elfm_view_mip *old = d->mips;
  size_t n_old = d->n_mips;
  d->mips = NULL;
  d->n_mips = 0;
  elfm_status st = mips_scan(dir, &fc, d, err);
  if (st == ELFM_OK && d->n_mips == 0)
    st = elfm_error_set(err, ELFM_ERR_FORMAT, dir, -1,
                        "no MIP pictures (*.png) or volumes (*.exr) named with a time "
                        "(t<us>) or a frame number%s",
                        fc.valid ? "" : " (frame numbers need the frame column of tracks.csv)");
  if (st != ELFM_OK) {
    free(d->mips);
    d->mips = old;
    d->n_mips = n_old;
    return st;
  }
  free(old);
  return ELFM_OK;
}

void elfm_view_data_free(elfm_view_data *d)
{
  if (!d) return;
  series_free(&d->tracks);
  series_free(&d->truth);
  free(d->det_xyz_um);
  free(d->det_t_us);
  free(d->mips);
  free(d);
}
