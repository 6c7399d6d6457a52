/* tracks_write.c — detections.csv, tracks.csv, ISBI 2012 XML and TrackMate
 * XML writers (see elfm_tracks.h). */
#include "elfm_tracks.h"

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

/* A CSV field: empty for a value that is not finite (the table reader
 * reads an empty field as "no value"). */
static void put_num(FILE *f, double v, const char *fmt)
{
  fputc(',', f);
  if (isfinite(v)) fprintf(f, fmt, v);
}

elfm_status elfm_detections_write_header(FILE *f, const char *path, elfm_error *err)
{
  fputs("frame,t_us,x_um,y_um,z_um,intensity,sigma_x_um,sigma_y_um,sigma_z_um,"
        "width_um,fit_sd_px,view_fit,weak\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_detections_write(FILE *f, const char *path, const elfm_detection *d, int n,
                                  elfm_error *err)
{
  for (int i = 0; i < n; i++) {
    fprintf(f, "%" PRId64 ",%" PRId64, d[i].frame, d[i].t_us);
    put_num(f, d[i].x_um, "%.4f");
    put_num(f, d[i].y_um, "%.4f");
    put_num(f, d[i].z_um, "%.4f");
    put_num(f, d[i].intensity, "%.6g");
    put_num(f, d[i].sigma_x_um, "%.4f");
    put_num(f, d[i].sigma_y_um, "%.4f");
    put_num(f, d[i].sigma_z_um, "%.4f");
    /* 0 in the struct means "not measured": written empty */
    put_num(f, d[i].width_um > 0 ? d[i].width_um : NAN, "%.4f");
    put_num(f, d[i].fit_sd_px > 0 ? d[i].fit_sd_px : NAN, "%.4f");
    fprintf(f, ",%d,%d\n", d[i].view_fit ? 1 : 0, d[i].weak ? 1 : 0);
  }
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_csv_header(FILE *f, const char *path, elfm_error *err)
{
  fputs("track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um,"
        "vx_um_per_ms,vy_um_per_ms,vz_um_per_ms,intensity,sd_x_um,sd_y_um,sd_z_um,"
        "sd_vx_um_per_ms,sd_vy_um_per_ms,sd_vz_um_per_ms\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_csv(FILE *f, const char *path, const elfm_track *t, elfm_error *err)
{
  if (!t->n_span || !t->pos_um || !t->raw_index || !t->n)
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1,
                          "track %" PRId64 " is empty or not smoothed", t->id);
  const int64_t frame0 = t->pts[0].frame;
  for (size_t k = 0; k < t->n_span; k++) {
    const double *p = t->pos_um + 3 * k, *v = t->vel_um_per_ms + 3 * k,
                 *sp = t->pos_sd_um + 3 * k, *sv = t->vel_sd_um_per_ms + 3 * k;
    fprintf(f, "%" PRId64 ",%" PRId64 ",%" PRId64, t->id, frame0 + (int64_t)k, t->span_t_us[k]);
    for (int a = 0; a < 3; a++) put_num(f, p[a], "%.4f");
    int32_t r = t->raw_index[k];
    if (r >= 0) {
      const elfm_detection *d = &t->pts[r];
      put_num(f, d->x_um, "%.4f");
      put_num(f, d->y_um, "%.4f");
      put_num(f, d->z_um, "%.4f");
    } else {
      fputs(",,,", f);
    }
    for (int a = 0; a < 3; a++) put_num(f, v[a], "%.5f");
    put_num(f, r >= 0 ? t->pts[r].intensity : NAN, "%.6g");
    for (int a = 0; a < 3; a++) put_num(f, sp[a], "%.4f");
    for (int a = 0; a < 3; a++) put_num(f, sv[a], "%.5f");
    fputc('\n', f);
  }
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

elfm_status elfm_tracks_write_isbi_begin(FILE *f, const char *path, elfm_error *err)
{
  fputs("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n<root>\n"
        "<TrackContestISBI2012 SNR=\"0\" density=\"unknown\" generationDateTime=\"\" "
        "info=\"eventlfm track; x, y, z in um, t = frame index\" scenario=\"eventlfm\">\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_isbi_track(FILE *f, const char *path, const elfm_track *t,
                                         elfm_error *err)
{
  fputs("<particle>\n", f);
  for (size_t j = 0; j < t->n; j++) {
    double p[3];
    point_pos(t, j, p);
    fprintf(f, "<detection t=\"%" PRId64 "\" x=\"%.4f\" y=\"%.4f\" z=\"%.4f\"/>\n",
            t->pts[j].frame, p[0], p[1], p[2]);
  }
  fputs("</particle>\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_isbi_end(FILE *f, const char *path, elfm_error *err)
{
  fputs("</TrackContestISBI2012>\n</root>\n", f);
  return io_check(f, path, err);
}

elfm_status elfm_tracks_write_isbi(FILE *f, const char *path, const elfm_track_store *s,
                                   elfm_error *err)
{
  elfm_status st = elfm_tracks_write_isbi_begin(f, path, err);
  for (size_t i = 0; st == ELFM_OK && i < s->n; i++)
    st = elfm_tracks_write_isbi_track(f, path, s->tracks[i], err);
  return st == ELFM_OK ? elfm_tracks_write_isbi_end(f, path, err) : st;
}

/* ---- TrackMate ----
 * A spot as it waits in the scratch file: everything its <Spot> line
 * needs, so the line is the same whether written at once or after the
 * sort. */
typedef struct tm_spot {
  int64_t frame;
  uint64_t id;
  double xyz_um[3], intensity, radius_um;
} tm_spot;

/* A track's entry under AllTracks: its spots' IDs are first_id .. first_id + n - 1. */
typedef struct tm_track {
  int64_t id;
  uint64_t first_id, n;
} tm_track;

/* Frames per block of the finishing sort: passes take whole blocks. */
#define TM_BLOCK_FRAMES 1024
#define TM_DEFAULT_SORT_SPOTS ((size_t)1 << 18)

struct elfm_trackmate_writer {
  char path[1024];     /* the output, for messages */
  char scratch[1100];  /* path + ".spots.tmp"; "" once removed */
  FILE *f;             /* the scratch file */
  double interval_ms;
  size_t max_sort;
  uint64_t n_spots;
  int64_t frame_min, frame_max;
  tm_track *tr;
  size_t n_tr, cap_tr;
};

static int tm_spot_cmp(const void *a, const void *b)
{
  const tm_spot *x = a, *y = b;
  if (x->frame != y->frame) return x->frame < y->frame ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

elfm_trackmate_writer *elfm_trackmate_writer_create(const char *path, double frame_interval_ms,
                                                    size_t max_sort_spots, elfm_error *err)
{
  if (!(frame_interval_ms > 0) || !isfinite(frame_interval_ms)) {
    elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "TrackMate: frame interval must be > 0");
    return NULL;
  }
  elfm_trackmate_writer *w = calloc(1, sizeof *w);
  if (!w) {
    elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "TrackMate: out of memory");
    return NULL;
  }
  snprintf(w->path, sizeof w->path, "%s", path);
  snprintf(w->scratch, sizeof w->scratch, "%s.spots.tmp", path);
  w->interval_ms = frame_interval_ms;
  w->max_sort = max_sort_spots ? max_sort_spots : TM_DEFAULT_SORT_SPOTS;
  w->frame_min = INT64_MAX;
  w->frame_max = INT64_MIN;
  w->f = fopen(w->scratch, "w+b");
  if (!w->f) {
    elfm_error_set(err, ELFM_ERR_IO, w->scratch, -1, "TrackMate: cannot create scratch file: %s",
                   strerror(errno));
    free(w);
    return NULL;
  }
  /* open files outlive their name on POSIX: gone however the run ends */
  if (remove(w->scratch) == 0) w->scratch[0] = '\0';
  return w;
}

void elfm_trackmate_writer_free(elfm_trackmate_writer *w)
{
  if (!w) return;
  if (w->f) fclose(w->f);
  if (w->scratch[0]) remove(w->scratch);
  free(w->tr);
  free(w);
}

elfm_status elfm_trackmate_writer_add(elfm_trackmate_writer *w, const elfm_track *t,
                                      elfm_error *err)
{
  if (w->n_tr == w->cap_tr) {
    size_t cap = w->cap_tr ? 2 * w->cap_tr : 64;
    tm_track *p = realloc(w->tr, cap * sizeof *p);
    if (!p) return elfm_error_set(err, ELFM_ERR_NOMEM, w->path, -1, "TrackMate: out of memory");
    w->tr = p;
    w->cap_tr = cap;
  }
  w->tr[w->n_tr++] = (tm_track){t->id, w->n_spots, t->n};
  for (size_t j = 0; j < t->n; j++) {
    const elfm_detection *d = &t->pts[j];
    tm_spot r;
    memset(&r, 0, sizeof r);
    r.frame = d->frame;
    r.id = w->n_spots++;
    point_pos(t, j, r.xyz_um);
    r.intensity = isfinite(d->intensity) ? d->intensity : 0.0;
    r.radius_um = d->sigma_x_um > 0 ? 1.1774 * d->sigma_x_um : 1.0; /* half max radius */
    if (d->frame < w->frame_min) w->frame_min = d->frame;
    if (d->frame > w->frame_max) w->frame_max = d->frame;
    if (fwrite(&r, sizeof r, 1, w->f) != 1)
      return elfm_error_set(err, ELFM_ERR_IO, w->scratch[0] ? w->scratch : w->path, -1,
                            "TrackMate: scratch file: write failed: %s", strerror(errno));
  }
  return ELFM_OK;
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

/* One frame's spots sp[0 .. n), sorted by ID. */
static void tm_write_frame(FILE *f, const tm_spot *sp, size_t n, double interval_ms)
{
  const int64_t fr = sp[0].frame;
  fprintf(f, "      <SpotsInFrame frame=\"%" PRId64 "\">\n", fr);
  for (size_t k = 0; k < n; k++)
    fprintf(f, "        <Spot ID=\"%" PRIu64 "\" name=\"ID%" PRIu64 "\" QUALITY=\"%.6g\" POSITION_X=\"%.4f\" "
               "POSITION_Y=\"%.4f\" POSITION_Z=\"%.4f\" POSITION_T=\"%.6f\" FRAME=\"%" PRId64
               "\" RADIUS=\"%.4f\" VISIBILITY=\"1\" MEAN_INTENSITY_CH1=\"%.6g\" />\n",
            sp[k].id, sp[k].id, sp[k].intensity, sp[k].xyz_um[0], sp[k].xyz_um[1],
            sp[k].xyz_um[2], (double)fr * interval_ms, fr, sp[k].radius_um, sp[k].intensity);
  fputs("      </SpotsInFrame>\n", f);
}

static void tm_write_tracks(FILE *f, const elfm_trackmate_writer *w)
{
  fputs("    </AllSpots>\n    <AllTracks>\n", f);
  for (size_t i = 0; i < w->n_tr; i++) {
    const tm_track *t = &w->tr[i];
    fprintf(f, "      <Track name=\"Track_%" PRId64 "\" TRACK_ID=\"%zu\" TRACK_INDEX=\"%zu\" NUMBER_SPOTS=\"%" PRIu64 "\">\n",
            t->id, i, i, t->n);
    for (uint64_t j = 1; j < t->n; j++)
      fprintf(f, "        <Edge SPOT_SOURCE_ID=\"%" PRIu64 "\" SPOT_TARGET_ID=\"%" PRIu64 "\" LINK_COST=\"0\" />\n",
              t->first_id + j - 1, t->first_id + j);
    fputs("      </Track>\n", f);
  }
  fputs("    </AllTracks>\n    <FilteredTracks>\n", f);
  for (size_t i = 0; i < w->n_tr; i++) fprintf(f, "      <TrackID TRACK_ID=\"%zu\" />\n", i);
  fprintf(f, "    </FilteredTracks>\n  </Model>\n  <Settings>\n"
             "    <ImageData filename=\"\" folder=\"\" width=\"0\" height=\"0\" nslices=\"0\" "
             "nframes=\"0\" pixelwidth=\"1.0\" pixelheight=\"1.0\" voxeldepth=\"1.0\" "
             "timeinterval=\"%.6g\" />\n  </Settings>\n</TrackMate>\n", w->interval_ms);
}

/* Read the scratch file from its start: with buf, collect the spots whose
 * block lies in [b0, b1) into it (*m of them); with buf NULL, count every
 * block's spots into cnt. */
static elfm_status tm_scan(elfm_trackmate_writer *w, uint64_t *cnt, int64_t b0, int64_t b1,
                           tm_spot *buf, size_t *m, elfm_error *err)
{
  const char *name = w->scratch[0] ? w->scratch : w->path;
  if (fflush(w->f) != 0 || fseek(w->f, 0, SEEK_SET) != 0)
    return elfm_error_set(err, ELFM_ERR_IO, name, -1, "TrackMate: scratch file: %s", strerror(errno));
  tm_spot chunk[256];
  uint64_t seen = 0;
  while (seen < w->n_spots) {
    size_t want = w->n_spots - seen < 256 ? (size_t)(w->n_spots - seen) : 256;
    size_t got = fread(chunk, sizeof chunk[0], want, w->f);
    if (got != want)
      return elfm_error_set(err, ELFM_ERR_IO, name, (int64_t)((seen + got) * sizeof chunk[0]),
                            "TrackMate: scratch file: read failed");
    for (size_t k = 0; k < got; k++) {
      const int64_t b = (chunk[k].frame - w->frame_min) / TM_BLOCK_FRAMES;
      if (!buf) cnt[b]++;
      else if (b >= b0 && b < b1) buf[(*m)++] = chunk[k];
    }
    seen += got;
  }
  return ELFM_OK;
}

elfm_status elfm_trackmate_writer_finish(elfm_trackmate_writer *w, FILE *f, elfm_error *err)
{
  tm_write_header(f, w->n_spots);
  elfm_status st = ELFM_OK;
  uint64_t *cnt = NULL;
  tm_spot *buf = NULL;
  if (w->n_spots) {
    /* Count each block's spots, then take runs of whole blocks that fit
     * the budget: one pass when everything fits (most runs), a few for
     * an hour's recording, and the scratch file is read sequentially. */
    const int64_t nb = (w->frame_max - w->frame_min) / TM_BLOCK_FRAMES + 1;
    cnt = calloc((size_t)nb, sizeof *cnt);
    if (!cnt) st = elfm_error_set(err, ELFM_ERR_NOMEM, w->path, -1, "TrackMate: out of memory");
    if (st == ELFM_OK) st = tm_scan(w, cnt, 0, 0, NULL, NULL, err);
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
          buf_cap = 0;
          st = elfm_error_set(err, ELFM_ERR_NOMEM, w->path, -1, "TrackMate: out of memory");
          break;
        }
      }
      size_t m = 0;
      if (take) st = tm_scan(w, NULL, b0, b1, buf, &m, err);
      if (st != ELFM_OK) break;
      qsort(buf, m, sizeof *buf, tm_spot_cmp);
      for (size_t k = 0; k < m;) {
        size_t e = k + 1;
        while (e < m && buf[e].frame == buf[k].frame) e++;
        tm_write_frame(f, buf + k, e - k, w->interval_ms);
        k = e;
      }
      b0 = b1;
    }
  }
  free(cnt);
  free(buf);
  if (st != ELFM_OK) return st;
  tm_write_tracks(f, w);
  return io_check(f, w->path, err);
}

elfm_status elfm_tracks_write_trackmate(FILE *f, const char *path, const elfm_track_store *s,
                                        double frame_interval_ms, elfm_error *err)
{
  elfm_error e;
  elfm_error_clear(&e);
  elfm_trackmate_writer *w = elfm_trackmate_writer_create(path, frame_interval_ms, 0, &e);
  if (!w) {
    if (err) *err = e;
    return e.code;
  }
  elfm_status st = ELFM_OK;
  for (size_t i = 0; st == ELFM_OK && i < s->n; i++) st = elfm_trackmate_writer_add(w, s->tracks[i], err);
  if (st == ELFM_OK) st = elfm_trackmate_writer_finish(w, f, err);
  elfm_trackmate_writer_free(w);
  return st;
}
