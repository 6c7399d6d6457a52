/* tracks_write.c — detections.csv, tracks.csv, ISBI 2012 XML and TrackMate
 * XML writers (see elfm_tracks.h). */
#include "elfm_tracks.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
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

elfm_status elfm_tracks_write_isbi(FILE *f, const char *path, const elfm_track_store *s,
                                   elfm_error *err)
{
  fputs("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n<root>\n"
        "<TrackContestISBI2012 SNR=\"0\" density=\"unknown\" generationDateTime=\"\" "
        "info=\"eventlfm track; x, y, z in um, t = frame index\" scenario=\"eventlfm\">\n", f);
  for (size_t i = 0; i < s->n; i++) {
    const elfm_track *t = s->tracks[i];
    fputs("<particle>\n", f);
    for (size_t j = 0; j < t->n; j++) {
      double p[3];
      point_pos(t, j, p);
      fprintf(f, "<detection t=\"%" PRId64 "\" x=\"%.4f\" y=\"%.4f\" z=\"%.4f\"/>\n",
              t->pts[j].frame, p[0], p[1], p[2]);
    }
    fputs("</particle>\n", f);
  }
  fputs("</TrackContestISBI2012>\n</root>\n", f);
  return io_check(f, path, err);
}

typedef struct tm_spot {
  int64_t frame;
  size_t track, point, id;
} tm_spot;

static int tm_spot_cmp(const void *a, const void *b)
{
  const tm_spot *x = a, *y = b;
  if (x->frame != y->frame) return x->frame < y->frame ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

elfm_status elfm_tracks_write_trackmate(FILE *f, const char *path, const elfm_track_store *s,
                                        double frame_interval_ms, elfm_error *err)
{
  if (!(frame_interval_ms > 0) || !isfinite(frame_interval_ms))
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "TrackMate: frame interval must be > 0");
  size_t nspots = 0;
  for (size_t i = 0; i < s->n; i++) nspots += s->tracks[i]->n;
  /* Spots are grouped by frame in TrackMate files: sort an index once. */
  tm_spot *sp = malloc((nspots ? nspots : 1) * sizeof *sp);
  size_t *first_id = malloc((s->n ? s->n : 1) * sizeof *first_id);
  if (!sp || !first_id) {
    free(sp);
    free(first_id);
    return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "TrackMate: out of memory");
  }
  size_t id = 0, m = 0;
  for (size_t i = 0; i < s->n; i++) {
    first_id[i] = id;
    for (size_t j = 0; j < s->tracks[i]->n; j++)
      sp[m++] = (tm_spot){s->tracks[i]->pts[j].frame, i, j, id++};
  }
  qsort(sp, nspots, sizeof *sp, tm_spot_cmp);

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
  fprintf(f, "    <AllSpots nspots=\"%zu\">\n", nspots);
  for (size_t k = 0; k < nspots;) {
    int64_t fr = sp[k].frame;
    fprintf(f, "      <SpotsInFrame frame=\"%" PRId64 "\">\n", fr);
    for (; k < nspots && sp[k].frame == fr; k++) {
      const elfm_track *t = s->tracks[sp[k].track];
      const elfm_detection *d = &t->pts[sp[k].point];
      double p[3];
      point_pos(t, sp[k].point, p);
      double radius = d->sigma_x_um > 0 ? 1.1774 * d->sigma_x_um : 1.0; /* half max radius */
      fprintf(f, "        <Spot ID=\"%zu\" name=\"ID%zu\" QUALITY=\"%.6g\" POSITION_X=\"%.4f\" "
                 "POSITION_Y=\"%.4f\" POSITION_Z=\"%.4f\" POSITION_T=\"%.6f\" FRAME=\"%" PRId64
                 "\" RADIUS=\"%.4f\" VISIBILITY=\"1\" MEAN_INTENSITY_CH1=\"%.6g\" />\n",
              sp[k].id, sp[k].id, isfinite(d->intensity) ? d->intensity : 0.0, p[0], p[1], p[2],
              (double)fr * frame_interval_ms, fr, radius,
              isfinite(d->intensity) ? d->intensity : 0.0);
    }
    fputs("      </SpotsInFrame>\n", f);
  }
  fputs("    </AllSpots>\n    <AllTracks>\n", f);
  for (size_t i = 0; i < s->n; i++) {
    const elfm_track *t = s->tracks[i];
    fprintf(f, "      <Track name=\"Track_%" PRId64 "\" TRACK_ID=\"%zu\" TRACK_INDEX=\"%zu\" NUMBER_SPOTS=\"%zu\">\n",
            t->id, i, i, t->n);
    for (size_t j = 1; j < t->n; j++)
      fprintf(f, "        <Edge SPOT_SOURCE_ID=\"%zu\" SPOT_TARGET_ID=\"%zu\" LINK_COST=\"0\" />\n",
              first_id[i] + j - 1, first_id[i] + j);
    fputs("      </Track>\n", f);
  }
  fputs("    </AllTracks>\n    <FilteredTracks>\n", f);
  for (size_t i = 0; i < s->n; i++) fprintf(f, "      <TrackID TRACK_ID=\"%zu\" />\n", i);
  fprintf(f, "    </FilteredTracks>\n  </Model>\n  <Settings>\n"
             "    <ImageData filename=\"\" folder=\"\" width=\"0\" height=\"0\" nslices=\"0\" "
             "nframes=\"0\" pixelwidth=\"1.0\" pixelheight=\"1.0\" voxeldepth=\"1.0\" "
             "timeinterval=\"%.6g\" />\n  </Settings>\n</TrackMate>\n", frame_interval_ms);
  free(sp);
  free(first_id);
  return io_check(f, path, err);
}
