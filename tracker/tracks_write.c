/* tracks_write.c — detections.csv, tracks.csv, ISBI 2012 XML and TrackMate
 * XML writers (see elfm_tracks.h). */
#include "elfm_tracks.h"
#include "fmt_num.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static elfm_status io_check(FILE *f, const char *path, elfm_error *err)
{
  if (ferror(f))
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

/* Rows as they are built: numbers go in through fmt_num.c (printf's text
 * without printf's cost, ~4 % of a track run on one thread), and the rows
 * out ~2 KB at a time, one fwrite each. A row that outgrows the buffer
 * (values near DBL_MAX take 330 characters each) goes out in pieces. */
typedef struct row {
  FILE *f;
  size_t n;
  char b[4096];
} row;

static void row_room(row *r, size_t need)
{
  if (r->n + need > sizeof r->b) {
    fwrite(r->b, 1, r->n, r->f);
    r->n = 0;
  }
}

static void row_end(row *r)
{
  fwrite(r->b, 1, r->n, r->f);
  r->n = 0;
}

static void row_str(row *r, const char *s)
{
  const size_t n = strlen(s);
  if (n > sizeof r->b) { /* not one of ours: every literal below is short */
    row_end(r);
    fputs(s, r->f);
    return;
  }
  row_room(r, n);
  memcpy(r->b + r->n, s, n);
  r->n += n;
}

static void row_i64(row *r, int64_t v)
{
  row_room(r, 24);
  r->n += elfm_fmt_i64(r->b + r->n, v);
}

static void row_u64(row *r, uint64_t v)
{
  row_room(r, 24);
  r->n += elfm_fmt_u64(r->b + r->n, v);
}

/* v as "%.<decimals>f" */
static void row_fix(row *r, double v, int decimals)
{
  row_room(r, ELFM_FMT_NUM_MAX);
  r->n += elfm_fmt_fixed(r->b + r->n, v, decimals);
}

/* v as "%.6g" (intensities: printf, one or two per row) */
static void row_g6(row *r, double v)
{
  row_room(r, 32);
  const int n = snprintf(r->b + r->n, 32, "%.6g", v);
  if (n > 0) r->n += (size_t)n < 32 ? (size_t)n : 31;
}

/* A CSV field: empty for a value that is not finite (the table reader
 * reads an empty field as "no value"); decimals < 0: "%.6g". */
static void put_num(row *r, double v, int decimals)
{
  row_room(r, 1);
  r->b[r->n++] = ',';
  if (!isfinite(v)) return;
  if (decimals < 0) row_g6(r, v);
  else row_fix(r, v, decimals);
}

#define G6 (-1)

elfm_status elfm_detections_write_header(FILE *f, const char *path, elfm_error *err)
{
  fputs("frame,t_us,x_um,y_um,z_um,intensity,sigma_x_um,sigma_y_um,sigma_z_um,"
        "width_um,fit_sd_px,view_fit,weak,nearest_um,claims,raw_x_um,raw_y_um,raw_z_um\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_detections_write(FILE *f, const char *path, const elfm_detection *d,
                                  const double *bias_um, int n, elfm_error *err)
{
  row r;
  r.f = f;
  r.n = 0;
  for (int i = 0; i < n; i++) {
    const double *b = bias_um ? bias_um + 3 * (size_t)i : NULL;
    row_i64(&r, d[i].frame);
    row_str(&r, ",");
    row_i64(&r, d[i].t_us);
    put_num(&r, b ? d[i].x_um - b[0] : d[i].x_um, 4);
    put_num(&r, b ? d[i].y_um - b[1] : d[i].y_um, 4);
    put_num(&r, b ? d[i].z_um - b[2] : d[i].z_um, 4);
    put_num(&r, d[i].intensity, G6);
    put_num(&r, d[i].sigma_x_um, 4);
    put_num(&r, d[i].sigma_y_um, 4);
    put_num(&r, d[i].sigma_z_um, 4);
    /* 0 in the struct means "not measured": written empty */
    put_num(&r, d[i].width_um > 0 ? d[i].width_um : NAN, 4);
    put_num(&r, d[i].fit_sd_px > 0 ? d[i].fit_sd_px : NAN, 4);
    row_str(&r, d[i].view_fit ? ",1" : ",0");
    row_str(&r, d[i].weak ? ",1" : ",0");
    put_num(&r, d[i].nearest_um > 0 ? d[i].nearest_um : NAN, 3);
    row_str(&r, ",");
    row_i64(&r, d[i].claims);
    put_num(&r, d[i].x_um, 4);
    put_num(&r, d[i].y_um, 4);
    put_num(&r, d[i].z_um, 4);
    row_str(&r, "\n");
    if (r.n > sizeof r.b / 2) row_end(&r);
  }
  row_end(&r);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_csv_header(FILE *f, const char *path, elfm_error *err)
{
  fputs("track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um,"
        "vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,intensity,sd_x_um,sd_y_um,sd_z_um,"
        "sd_vx_um_per_ms,sd_vy_um_per_ms,sd_vz_um_per_ms,nearest_um,claims\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_csv(FILE *f, const char *path, const elfm_track *t, elfm_error *err)
{
  if (!t->n_span || !t->pos_um || !t->raw_index || !t->n)
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1,
                          "track %" PRId64 " is empty or not smoothed", t->id);
  const int64_t frame0 = t->pts[0].frame;
  const int v_known = elfm_track_velocity_known(t);
  row w;
  w.f = f;
  w.n = 0;
  for (size_t k = 0; k < t->n_span; k++) {
    if (!elfm_track_writes_frame(t, frame0 + (int64_t)k)) continue; /* a piece's context */
    const double *p = t->pos_um + 3 * k, *v = t->vel_um_per_ms + 3 * k,
                 *sp = t->pos_sd_um + 3 * k, *sv = t->vel_sd_um_per_ms + 3 * k;
    row_i64(&w, t->id);
    row_str(&w, ",");
    row_i64(&w, frame0 + (int64_t)k);
    row_str(&w, ",");
    row_i64(&w, t->span_t_us[k]);
    for (int a = 0; a < 3; a++) put_num(&w, p[a], 4);
    int32_t r = t->raw_index[k];
    if (r >= 0) {
      const elfm_detection *d = &t->pts[r];
      put_num(&w, d->x_um, 4);
      put_num(&w, d->y_um, 4);
      put_num(&w, d->z_um, 4);
    } else {
      row_str(&w, ",,,");
    }
    /* a track of one frame has no measured velocity (elfm_track_velocity_known) */
    for (int a = 0; a < 3; a++) put_num(&w, v_known ? v[a] : NAN, 5);
    put_num(&w, r >= 0 ? t->pts[r].intensity : NAN, G6);
    for (int a = 0; a < 3; a++) put_num(&w, sp[a], 4);
    for (int a = 0; a < 3; a++) put_num(&w, v_known ? sv[a] : NAN, 5);
    put_num(&w, r >= 0 && t->pts[r].nearest_um > 0 ? t->pts[r].nearest_um : NAN, 3);
    if (r >= 0) {
      row_str(&w, ",");
      row_i64(&w, t->pts[r].claims);
      row_str(&w, "\n");
    } else {
      row_str(&w, ",\n");
    }
    if (w.n > sizeof w.b / 2) row_end(&w);
  }
  row_end(&w);
  return io_check(f, path, err);
}

/* Position written for real point j: smoothed when available, else raw. */
static void point_pos(const elfm_track *t, size_t j, double xyz[3])
{
  size_t k = (size_t)(t->pts[j].frame - t->pts[0].frame);
  if (t->pos_um && k < t->n_span && isfinite(t->pos_um[3 * k])) {
    memcpy(xyz, t->pos_um + 3 * k, 3 * sizeof(double));
  } else {
    xyz[0] = t->pts[j].x_um;
    xyz[1] = t->pts[j].y_um;
    xyz[2] = t->pts[j].z_um;
  }
}

/* ---- ISBI 2012 ---- */

static void isbi_begin(FILE *f)
{
  fputs("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n<root>\n"
        "<TrackContestISBI2012 SNR=\"0\" density=\"unknown\" generationDateTime=\"\" "
        "info=\"eventlfm track; x, y, z in um, t = frame index\" scenario=\"eventlfm\">\n", f);
}

static void isbi_detection(FILE *f, int64_t frame, const double p[3])
{
  row r;
  r.f = f;
  r.n = 0;
  row_str(&r, "<detection t=\"");
  row_i64(&r, frame);
  row_str(&r, "\" x=\"");
  row_fix(&r, p[0], 4);
  row_str(&r, "\" y=\"");
  row_fix(&r, p[1], 4);
  row_str(&r, "\" z=\"");
  row_fix(&r, p[2], 4);
  row_str(&r, "\"/>\n");
  row_end(&r);
}

static void isbi_end(FILE *f) { fputs("</TrackContestISBI2012>\n</root>\n", f); }

elfm_status elfm_tracks_write_isbi(FILE *f, const char *path, const elfm_track_store *s,
                                   elfm_error *err)
{
  isbi_begin(f);
  for (size_t i = 0; i < s->n; i++) {
    const elfm_track *t = s->tracks[i];
    fputs("<particle>\n", f);
    for (size_t j = 0; j < t->n; j++) {
      if (!elfm_track_writes_frame(t, t->pts[j].frame)) continue;
      double p[3];
      point_pos(t, j, p);
      isbi_detection(f, t->pts[j].frame, p);
    }
    fputs("</particle>\n", f);
  }
  isbi_end(f);
  return io_check(f, path, err);
}

/* ---- Both XML files from tracks given as they end ----
 * A real point as it waits in the scratch file: everything its ISBI
 * <detection> and TrackMate <Spot> lines need, so each line is the same
 * whether written at once or after the sort. */
typedef struct xml_spot {
  int64_t entry;    /* its track's entry (order of first appearance) */
  int64_t frame;
  uint64_t id;      /* TrackMate spot ID: in the order the points came */
  double xyz_um[3], intensity, radius_um;
} xml_spot;

/* A track: its pieces' spot IDs are first_id .. first_id + n - 1 each,
 * linked through next (SIZE_MAX ends). */
typedef struct xml_piece {
  uint64_t first_id, n;
  size_t next;
} xml_piece;

typedef struct xml_track {
  int64_t id;
  uint64_t n;
  size_t first_piece, last_piece;
} xml_track;

/* Passes over the scratch file take whole blocks: of 1024 frames (sorted
 * by frame, TrackMate) or of 64 tracks (by track, ISBI). */
#define XML_BLOCK_FRAMES 1024
#define XML_BLOCK_TRACKS 64
#define XML_DEFAULT_SORT_SPOTS ((size_t)1 << 18)

struct elfm_track_xml {
  char scratch[1100];  /* its name; "" once removed */
  FILE *f;             /* the scratch file */
  size_t max_sort;
  uint64_t n_spots;
  int64_t frame_min, frame_max;
  xml_track *tr;
  size_t n_tr, cap_tr;
  xml_piece *pc;
  size_t n_pc, cap_pc;
};

elfm_track_xml *elfm_track_xml_create(const char *scratch_path, size_t max_sort_spots,
                                      elfm_error *err)
{
  elfm_track_xml *w = calloc(1, sizeof *w);
  if (!w) {
    elfm_error_set(err, ELFM_ERR_NOMEM, scratch_path, -1, "track XML: out of memory");
    return NULL;
  }
  snprintf(w->scratch, sizeof w->scratch, "%s", scratch_path);
  w->max_sort = max_sort_spots ? max_sort_spots : XML_DEFAULT_SORT_SPOTS;
  w->frame_min = INT64_MAX;
  w->frame_max = INT64_MIN;
  w->f = fopen(w->scratch, "w+b");
  if (!w->f) {
    elfm_error_set(err, ELFM_ERR_IO, scratch_path, -1, "cannot create scratch file: %s",
                   strerror(errno));
    free(w);
    return NULL;
  }
  /* open files outlive their name on POSIX: gone however the run ends */
  if (remove(w->scratch) == 0) w->scratch[0] = '\0';
  return w;
}

void elfm_track_xml_free(elfm_track_xml *w)
{
  if (!w) return;
  if (w->f) fclose(w->f);
  if (w->scratch[0]) remove(w->scratch);
  free(w->tr);
  free(w->pc);
  free(w);
}

static elfm_status xml_nomem(elfm_error *err)
{
  return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "track XML: out of memory");
}

/* The entry of a later piece's track: searched from the newest, where the
 * long tracks that are still running tend to be. */
static size_t xml_find(const elfm_track_xml *w, int64_t id)
{
  for (size_t e = w->n_tr; e-- > 0;)
    if (w->tr[e].id == id) return e;
  return SIZE_MAX;
}

elfm_status elfm_track_xml_add(elfm_track_xml *w, const elfm_track *t, elfm_error *err)
{
  if (w->n_tr == w->cap_tr || w->n_pc == w->cap_pc) {
    size_t ct = w->n_tr == w->cap_tr ? (w->cap_tr ? 2 * w->cap_tr : 64) : w->cap_tr;
    size_t cp = w->n_pc == w->cap_pc ? (w->cap_pc ? 2 * w->cap_pc : 64) : w->cap_pc;
    xml_track *a = realloc(w->tr, ct * sizeof *a);
    if (!a) return xml_nomem(err);
    w->tr = a;
    w->cap_tr = ct;
    xml_piece *b = realloc(w->pc, cp * sizeof *b);
    if (!b) return xml_nomem(err);
    w->pc = b;
    w->cap_pc = cp;
  }
  size_t own = 0;
  for (size_t j = 0; j < t->n; j++) own += elfm_track_writes_frame(t, t->pts[j].frame);
  if (!own) return ELFM_OK;
  size_t e = t->partial && t->piece > 0 ? xml_find(w, t->id) : SIZE_MAX;
  const size_t p = w->n_pc++;
  w->pc[p] = (xml_piece){w->n_spots, own, SIZE_MAX};
  if (e == SIZE_MAX) {
    e = w->n_tr++;
    w->tr[e] = (xml_track){t->id, 0, p, p};
  } else {
    w->pc[w->tr[e].last_piece].next = p;
    w->tr[e].last_piece = p;
  }
  w->tr[e].n += own;
  for (size_t j = 0; j < t->n; j++) {
    const elfm_detection *d = &t->pts[j];
    if (!elfm_track_writes_frame(t, d->frame)) continue;
    xml_spot r;
    memset(&r, 0, sizeof r);
    r.entry = (int64_t)e;
    r.frame = d->frame;
    r.id = w->n_spots++;
    point_pos(t, j, r.xyz_um);
    r.intensity = isfinite(d->intensity) ? d->intensity : 0.0;
    r.radius_um = d->sigma_x_um > 0 ? 1.1774 * d->sigma_x_um : 1.0; /* half max radius */
    if (d->frame < w->frame_min) w->frame_min = d->frame;
    if (d->frame > w->frame_max) w->frame_max = d->frame;
    if (fwrite(&r, sizeof r, 1, w->f) != 1)
      return elfm_error_set(err, ELFM_ERR_IO, w->scratch, -1, "scratch file: write failed: %s",
                            strerror(errno));
  }
  return ELFM_OK;
}

static int64_t xml_block(const elfm_track_xml *w, const xml_spot *r, int by_frame)
{
  return by_frame ? (r->frame - w->frame_min) / XML_BLOCK_FRAMES : r->entry / XML_BLOCK_TRACKS;
}

static int xml_cmp_frame(const void *a, const void *b)
{
  const xml_spot *x = a, *y = b;
  if (x->frame != y->frame) return x->frame < y->frame ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

static int xml_cmp_track(const void *a, const void *b)
{
  const xml_spot *x = a, *y = b;
  if (x->entry != y->entry) return x->entry < y->entry ? -1 : 1;
  return (x->frame > y->frame) - (x->frame < y->frame);
}

/* Read the scratch file from its start: with buf, collect the spots whose
 * block lies in [b0, b1) into it (*m of them); with buf NULL, count every
 * block's spots into cnt. */
static elfm_status xml_scan(elfm_track_xml *w, int by_frame, uint64_t *cnt, int64_t b0,
                           int64_t b1, xml_spot *buf, size_t *m, elfm_error *err)
{
  const char *name = w->scratch[0] ? w->scratch : "scratch file";
  if (fflush(w->f) != 0 || fseek(w->f, 0, SEEK_SET) != 0)
    return elfm_error_set(err, ELFM_ERR_IO, name, -1, "scratch file: %s", strerror(errno));
  xml_spot chunk[256];
  uint64_t seen = 0;
  while (seen < w->n_spots) {
    size_t want = w->n_spots - seen < 256 ? (size_t)(w->n_spots - seen) : 256;
    size_t got = fread(chunk, sizeof chunk[0], want, w->f);
    if (got != want)
      return elfm_error_set(err, ELFM_ERR_IO, name, (int64_t)((seen + got) * sizeof chunk[0]),
                            "scratch file: read failed");
    for (size_t k = 0; k < got; k++) {
      const int64_t b = xml_block(w, &chunk[k], by_frame);
      if (!buf) cnt[b]++;
      else if (b >= b0 && b < b1) buf[(*m)++] = chunk[k];
    }
    seen += got;
  }
  return ELFM_OK;
}

/* Every spot once, sorted by frame (by_frame) or by track, handed to emit
 * a pass at a time. Each block's spots are counted first; each pass then
 * takes a run of whole blocks that fits the budget: one pass when
 * everything fits (most runs), a few for hours of recording, and the
 * scratch file is only ever read from start to end. */
typedef void (*xml_emit_fn)(FILE *f, const elfm_track_xml *w, const xml_spot *s, size_t n,
                            double interval_ms);

static elfm_status xml_sorted(elfm_track_xml *w, int by_frame, FILE *f, xml_emit_fn emit,
                              double interval_ms, elfm_error *err)
{
  if (!w->n_spots) return ELFM_OK;
  const int64_t nb = by_frame ? (w->frame_max - w->frame_min) / XML_BLOCK_FRAMES + 1
                              : (int64_t)(w->n_tr - 1) / XML_BLOCK_TRACKS + 1;
  uint64_t *cnt = calloc((size_t)nb, sizeof *cnt);
  if (!cnt) return xml_nomem(err);
  elfm_status st = xml_scan(w, by_frame, cnt, 0, 0, NULL, NULL, err);
  xml_spot *buf = NULL;
  size_t buf_cap = 0;
  for (int64_t b0 = 0; st == ELFM_OK && b0 < nb;) {
    int64_t b1 = b0 + 1;
    uint64_t take = cnt[b0];
    while (b1 < nb && take + cnt[b1] <= w->max_sort) take += cnt[b1++];
    if (take > buf_cap) {
      free(buf);
      buf_cap = (size_t)take;
      buf = malloc(buf_cap * sizeof *buf);
      if (!buf) {
        st = xml_nomem(err);
        break;
      }
    }
    size_t m = 0;
    if (take) st = xml_scan(w, by_frame, NULL, b0, b1, buf, &m, err);
    if (st != ELFM_OK) break;
    qsort(buf, m, sizeof *buf, by_frame ? xml_cmp_frame : xml_cmp_track);
    for (size_t k = 0; k < m;) { /* one call per frame, or per track */
      size_t e = k + 1;
      while (e < m && (by_frame ? buf[e].frame == buf[k].frame : buf[e].entry == buf[k].entry)) e++;
      emit(f, w, buf + k, e - k, interval_ms);
      k = e;
    }
    b0 = b1;
  }
  free(cnt);
  free(buf);
  return st;
}

static void isbi_particle(FILE *f, const elfm_track_xml *w, const xml_spot *s, size_t n,
                          double interval_ms)
{
  (void)w;
  (void)interval_ms;
  fputs("<particle>\n", f);
  for (size_t k = 0; k < n; k++) isbi_detection(f, s[k].frame, s[k].xyz_um);
  fputs("</particle>\n", f);
}

elfm_status elfm_track_xml_write_isbi(elfm_track_xml *w, FILE *f, const char *path,
                                      elfm_error *err)
{
  isbi_begin(f);
  elfm_status st = xml_sorted(w, 0, f, isbi_particle, 0, err);
  if (st != ELFM_OK) return st;
  isbi_end(f);
  return io_check(f, path, err);
}

static void tm_write_header(FILE *f, uint64_t nspots)
{
  fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<TrackMate version=\"7.0.0\">\n"
        "  <Model spatialunits=\"micron\" timeunits=\"ms\">\n"
        "    <FeatureDeclarations>\n      <SpotFeatures>\n", f);
  static const char *const spot_feat[][3] = {
      {"QUALITY", "NONE", "false"},      {"POSITION_X", "POSITION", "false"},
      {"POSITION_Y", "POSITION", "false"}, {"POSITION_Z", "POSITION", "false"},
      {"POSITION_T", "TIME", "false"},   {"FRAME", "NONE", "true"},
      {"RADIUS", "LENGTH", "false"},     {"VISIBILITY", "NONE", "true"},
      {"MEAN_INTENSITY_CH1", "INTENSITY", "false"}};
  for (size_t k = 0; k < sizeof spot_feat / sizeof spot_feat[0]; k++)
    fprintf(f, "        <Feature feature=\"%s\" name=\"%s\" shortname=\"%s\" dimension=\"%s\" isint=\"%s\" />\n",
            spot_feat[k][0], spot_feat[k][0], spot_feat[k][0], spot_feat[k][1], spot_feat[k][2]);
  fputs("      </SpotFeatures>\n      <EdgeFeatures>\n"
        "        <Feature feature=\"SPOT_SOURCE_ID\" name=\"Source spot ID\" shortname=\"Source ID\" dimension=\"NONE\" isint=\"true\" />\n"
        "        <Feature feature=\"SPOT_TARGET_ID\" name=\"Target spot ID\" shortname=\"Target ID\" dimension=\"NONE\" isint=\"true\" />\n"
        "        <Feature feature=\"LINK_COST\" name=\"Edge cost\" shortname=\"Cost\" dimension=\"NONE\" isint=\"false\" />\n"
        "      </EdgeFeatures>\n      <TrackFeatures>\n"
        "        <Feature feature=\"TRACK_ID\" name=\"Track ID\" shortname=\"ID\" dimension=\"NONE\" isint=\"true\" />\n"
        "        <Feature feature=\"TRACK_INDEX\" name=\"Track index\" shortname=\"Index\" dimension=\"NONE\" isint=\"true\" />\n"
        "        <Feature feature=\"NUMBER_SPOTS\" name=\"Number of spots in track\" shortname=\"N spots\" dimension=\"NONE\" isint=\"true\" />\n"
        "      </TrackFeatures>\n    </FeatureDeclarations>\n", f);
  fprintf(f, "    <AllSpots nspots=\"%" PRIu64 "\">\n", nspots);
}

/* One frame's spots, sorted by ID. */
static void tm_write_frame(FILE *f, const elfm_track_xml *w, const xml_spot *sp, size_t n,
                           double interval_ms)
{
  (void)w;
  const int64_t fr = sp[0].frame;
  fprintf(f, "      <SpotsInFrame frame=\"%" PRId64 "\">\n", fr);
  row r;
  r.f = f;
  r.n = 0;
  for (size_t k = 0; k < n; k++) {
    row_str(&r, "        <Spot ID=\"");
    row_u64(&r, sp[k].id);
    row_str(&r, "\" name=\"ID");
    row_u64(&r, sp[k].id);
    row_str(&r, "\" QUALITY=\"");
    row_g6(&r, sp[k].intensity);
    row_str(&r, "\" POSITION_X=\"");
    row_fix(&r, sp[k].xyz_um[0], 4);
    row_str(&r, "\" POSITION_Y=\"");
    row_fix(&r, sp[k].xyz_um[1], 4);
    row_str(&r, "\" POSITION_Z=\"");
    row_fix(&r, sp[k].xyz_um[2], 4);
    row_str(&r, "\" POSITION_T=\"");
    row_fix(&r, (double)fr * interval_ms, 6);
    row_str(&r, "\" FRAME=\"");
    row_i64(&r, fr);
    row_str(&r, "\" RADIUS=\"");
    row_fix(&r, sp[k].radius_um, 4);
    row_str(&r, "\" VISIBILITY=\"1\" MEAN_INTENSITY_CH1=\"");
    row_g6(&r, sp[k].intensity);
    row_str(&r, "\" />\n");
    if (r.n > sizeof r.b / 2) row_end(&r);
  }
  row_end(&r);
  fputs("      </SpotsInFrame>\n", f);
}

/* AllTracks: each track's spots in the order they came, piece after piece,
 * one edge between each two. */
static void tm_write_tracks(FILE *f, const elfm_track_xml *w, double interval_ms)
{
  fputs("    </AllSpots>\n    <AllTracks>\n", f);
  for (size_t i = 0; i < w->n_tr; i++) {
    const xml_track *t = &w->tr[i];
    fprintf(f, "      <Track name=\"Track_%" PRId64 "\" TRACK_ID=\"%zu\" TRACK_INDEX=\"%zu\" NUMBER_SPOTS=\"%" PRIu64 "\">\n",
            t->id, i, i, t->n);
    uint64_t prev = UINT64_MAX;
    for (size_t p = t->first_piece; p != SIZE_MAX; p = w->pc[p].next)
      for (uint64_t j = 0; j < w->pc[p].n; j++) {
        const uint64_t id = w->pc[p].first_id + j;
        if (prev != UINT64_MAX)
          fprintf(f, "        <Edge SPOT_SOURCE_ID=\"%" PRIu64 "\" SPOT_TARGET_ID=\"%" PRIu64 "\" LINK_COST=\"0\" />\n",
                  prev, id);
        prev = id;
      }
    fputs("      </Track>\n", f);
  }
  fputs("    </AllTracks>\n    <FilteredTracks>\n", f);
  for (size_t i = 0; i < w->n_tr; i++) fprintf(f, "      <TrackID TRACK_ID=\"%zu\" />\n", i);
  fprintf(f, "    </FilteredTracks>\n  </Model>\n  <Settings>\n"
             "    <ImageData filename=\"\" folder=\"\" width=\"0\" height=\"0\" nslices=\"0\" "
             "nframes=\"0\" pixelwidth=\"1.0\" pixelheight=\"1.0\" voxeldepth=\"1.0\" "
             "timeinterval=\"%.6g\" />\n  </Settings>\n</TrackMate>\n", interval_ms);
}

elfm_status elfm_track_xml_write_trackmate(elfm_track_xml *w, FILE *f, const char *path,
                                           double frame_interval_ms, elfm_error *err)
{
  if (!(frame_interval_ms > 0) || !isfinite(frame_interval_ms))
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "TrackMate: frame interval must be > 0");
  tm_write_header(f, w->n_spots);
  elfm_status st = xml_sorted(w, 1, f, tm_write_frame, frame_interval_ms, err);
  if (st != ELFM_OK) return st;
  tm_write_tracks(f, w, frame_interval_ms);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_trackmate(FILE *f, const char *path, const elfm_track_store *s,
                                        double frame_interval_ms, elfm_error *err)
{
  if (!(frame_interval_ms > 0) || !isfinite(frame_interval_ms))
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "TrackMate: frame interval must be > 0");
  char scratch[1100];
  snprintf(scratch, sizeof scratch, "%s.spots.tmp", path);
  elfm_error e;
  elfm_error_clear(&e);
  elfm_track_xml *w = elfm_track_xml_create(scratch, 0, &e);
  if (!w) {
    if (err) *err = e;
    return e.code;
  }
  elfm_status st = ELFM_OK;
  for (size_t i = 0; st == ELFM_OK && i < s->n; i++) st = elfm_track_xml_add(w, s->tracks[i], err);
  if (st == ELFM_OK) st = elfm_track_xml_write_trackmate(w, f, path, frame_interval_ms, err);
  elfm_track_xml_free(w);
  return st;
}
