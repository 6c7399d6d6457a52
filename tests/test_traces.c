/* test_traces.c — intensity traces per object (tracker/traces.c,
 * elfm_refocus_sample, `eventlfm traces`):
 *   - elfm_refocus_sample equals the refocused volume at a voxel and its
 *     trilinear interpolation between voxels; 0 outside and for NaN;
 *   - objects from tracks: rows in any order, positions linear in time,
 *     present only within the track unless held, `detected` from raw_x_um;
 *     a missing column names the file and the column, a bad value its line;
 *   - objects from detections: clusters within the radius, the dim joining
 *     the bright, small clusters dropped, numbered by first detection;
 *   - end to end on the `slice` scene (12 neurons, each flashing 1-6 ms
 *     every 100-600 ms): `eventlfm track` then `eventlfm traces
 *     --detections` finds each neuron that flashed as one object, and its
 *     trace's onsets are the stimulus's (measured: 33 of 33 flashes over 1
 *     s of seed 1, 310 of 311 over 3 s of seeds 2-4, no false onset, at
 *     value 20). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "check.h"
#include "cli_test_util.h"
#include "elfm_datasets.h"
#include "elfm_tracker.h"
#include "lfm_render.h"

static void paper_calib(elfm_calib *c)
{
  elfm_optics o;
  elfm_error err;
  elfm_optics_default(&o);
  CHECK_OK(elfm_calib_from_optics(&o, 1280, 720, 4.86, c, &err), &err);
}

static float vol_at(const elfm_volume *v, int X, int Y, int k)
{
  return v->data[((size_t)k * v->h + (size_t)Y) * v->w + (size_t)X];
}

static void test_sample(void)
{
  elfm_calib c;
  paper_calib(&c);
  elfm_error err;
  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  ro.agree_frac = 0; /* the plain mean of the views, as elfm_refocus_value_at */
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(&c, &ro, &p, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *v = elfm_refocus_volume_create(p, &err);
  elfm_frame *f = elfm_frame_create(c.sensor_width_px, c.sensor_height_px, &err);
  if (!p || !ws || !v || !f) return;
  render_views(f, &c, 12.3, -7.9, 21.7, 200.0, 1.6, 0, 0, 0);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, f, v, ws, &err), &err);
  float vmax = 0;
  int bx = 0, by = 0, bk = 0;
  for (int k = 0; k < v->nz; k++)
    for (int y = 0; y < v->h; y++)
      for (int x = 0; x < v->w; x++)
        if (vol_at(v, x, y, k) > vmax) vmax = vol_at(v, x, y, k), bx = x, by = y, bk = k;
  CHECK(vmax > 50);
  const double tol = 1e-4 * vmax;
  /* on voxels: the volume's value */
  for (int d = -2; d <= 2; d++) {
    CHECK_NEAR(elfm_refocus_sample(p, f, bx + d, by, bk), vol_at(v, bx + d, by, bk), tol);
    CHECK_NEAR(elfm_refocus_sample(p, f, bx, by + d, bk + 3 * d), vol_at(v, bx, by + d, bk + 3 * d),
               tol);
  }
  /* between voxels: trilinear */
  const double fx = 0.3, fy = 0.75, fk = 0.4;
  double want = 0;
  for (int c8 = 0; c8 < 8; c8++) {
    const int dx = c8 & 1, dy = (c8 >> 1) & 1, dk = c8 >> 2;
    want += (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dk ? fk : 1 - fk) *
            vol_at(v, bx - 1 + dx, by + dy, bk + dk);
  }
  CHECK_NEAR(elfm_refocus_sample(p, f, bx - 1 + fx, by + fy, bk + fk), want, tol);
  /* outside the volume, far off, NaN: 0 */
  CHECK(elfm_refocus_sample(p, f, -5, by, bk) == 0);
  CHECK(elfm_refocus_sample(p, f, bx, by, v->nz + 3) == 0);
  CHECK(elfm_refocus_sample(p, f, 1e300, by, bk) == 0);
  CHECK(elfm_refocus_sample(p, f, NAN, by, bk) == 0);
  elfm_frame_free(f);
  elfm_volume_free(v);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
}

/* A plan, an all-zero frame and the geometry, for the objects' rows. */
typedef struct geom {
  elfm_calib c;
  elfm_refocus_plan *p;
  elfm_volume *v;
  elfm_frame *f;
} geom;

static int geom_make(geom *g)
{
  elfm_error err;
  paper_calib(&g->c);
  CHECK_OK(elfm_refocus_plan_create(&g->c, NULL, &g->p, &err), &err);
  g->v = g->p ? elfm_refocus_volume_create(g->p, &err) : NULL;
  g->f = elfm_frame_create(g->c.sensor_width_px, g->c.sensor_height_px, &err);
  return g->p && g->v && g->f;
}

static void geom_free(geom *g)
{
  elfm_frame_free(g->f);
  elfm_volume_free(g->v);
  elfm_refocus_plan_free(g->p);
}

static void at(geom *g, int64_t t_us)
{
  g->f->t_us = t_us;
  g->f->t_start_us = t_us - 200; /* detections within 100 us count */
  g->f->t_end_us = t_us;
}

static elfm_table *table(const char *csv)
{
  elfm_table *t = NULL;
  elfm_error err;
  CHECK_OK(elfm_table_parse(csv, strlen(csv), "mem.csv", &t, &err), &err);
  return t;
}

static void test_from_tracks(void)
{
  geom g;
  if (!geom_make(&g)) return;
  /* track 5's rows out of order (a long track is written in pieces); its
   * 3000 us point was not a detection (raw empty) */
  elfm_table *t = table("track_id,frame,t_us,x_um,y_um,z_um,raw_x_um\n"
                        "7,2,3000,2,0,0,2\n"
                        "5,0,1000,0,0,0,0\n"
                        "5,2,3000,2,2,2,\n"
                        "5,1,2000,1,1,1,1\n"
                        "7,1,2000,1,0,0,1\n");
  elfm_error err;
  elfm_trace_objects *o = NULL;
  CHECK_OK(elfm_trace_objects_from_tracks(t, 0, &o, &err), &err);
  if (!o) return;
  CHECK_EQ_INT((int)elfm_trace_objects_count(o), 2);
  elfm_trace_object_info in;
  elfm_trace_objects_info(o, 0, &in);
  CHECK(in.id == 5 && in.n_points == 3 && in.n_detected == 2 && in.first_t_us == 1000 &&
        in.last_t_us == 3000);
  CHECK_NEAR(in.x_um, 1.0, 1e-12);
  elfm_trace_objects_info(o, 1, &in);
  CHECK(in.id == 7 && in.n_points == 2 && in.n_detected == 2);
  elfm_trace_row rows[2];
  at(&g, 500); /* before both */
  CHECK_EQ_INT((int)elfm_trace_objects_frame(o, g.p, g.f, g.v, rows), 0);
  at(&g, 1600); /* track 5 only, 0.6 of the way to its 2000 us point */
  size_t n = elfm_trace_objects_frame(o, g.p, g.f, g.v, rows);
  CHECK_EQ_INT((int)n, 1);
  CHECK(rows[0].id == 5);
  CHECK_NEAR(rows[0].x_um, 0.6, 1e-12);
  CHECK_NEAR(rows[0].z_um, 0.6, 1e-12);
  CHECK(rows[0].detected == 0); /* 1000 and 2000 us lie more than 100 us away */
  CHECK(rows[0].intensity == 0); /* an empty frame */
  at(&g, 2000);
  n = elfm_trace_objects_frame(o, g.p, g.f, g.v, rows);
  CHECK_EQ_INT((int)n, 2);
  CHECK(rows[0].detected == 1 && rows[1].detected == 1);
  at(&g, 3000);
  n = elfm_trace_objects_frame(o, g.p, g.f, g.v, rows);
  CHECK_EQ_INT((int)n, 2);
  CHECK(rows[0].id == 5 && rows[0].detected == 0); /* raw_x_um empty there */
  CHECK(rows[1].id == 7 && rows[1].detected == 1);
  CHECK_NEAR(rows[0].y_um, 2.0, 1e-12);
  at(&g, 3600); /* after both */
  CHECK_EQ_INT((int)elfm_trace_objects_frame(o, g.p, g.f, g.v, rows), 0);
  elfm_trace_objects_free(o);
  /* held: present from the start at the first point, after the end at the last */
  CHECK_OK(elfm_trace_objects_from_tracks(t, 1, &o, &err), &err);
  if (o) {
    at(&g, 100);
    n = elfm_trace_objects_frame(o, g.p, g.f, g.v, rows);
    CHECK_EQ_INT((int)n, 2);
    CHECK_NEAR(rows[1].x_um, 1.0, 1e-12);
    at(&g, 9000);
    n = elfm_trace_objects_frame(o, g.p, g.f, g.v, rows);
    CHECK_EQ_INT((int)n, 2);
    CHECK_NEAR(rows[0].x_um, 2.0, 1e-12);
    CHECK_NEAR(rows[1].x_um, 2.0, 1e-12);
    elfm_trace_objects_free(o);
  }
  elfm_table_free(t);
  /* a missing column names the file and the column; a bad value its line */
  t = table("track_id,frame,t_us,x_um,y_um\n1,0,1000,0,0\n");
  o = NULL;
  CHECK(elfm_trace_objects_from_tracks(t, 0, &o, &err) != ELFM_OK && !o);
  CHECK_MSG(strstr(err.message, "z_um") && strstr(err.file, "mem.csv"), "%s (%s)", err.message,
            err.file);
  elfm_table_free(t);
  /* the CSV parser refuses inf and nan; a table built in memory may not */
  t = table("track_id,t_us,x_um,y_um,z_um\n1,1000,0,0,0\n\n1,2000,7,0,0\n");
  if (t) t->values[1 * t->n_cols + 2] = INFINITY;
  CHECK(elfm_trace_objects_from_tracks(t, 0, &o, &err) != ELFM_OK && !o);
  CHECK_MSG(err.line == 4 && strstr(err.file, "mem.csv"), "%s:%lld", err.file, (long long)err.line);
  elfm_table_free(t);
  /* no rows: no objects, no rows per frame */
  t = table("track_id,t_us,x_um,y_um,z_um\n");
  CHECK_OK(elfm_trace_objects_from_tracks(t, 1, &o, &err), &err);
  if (o) {
    CHECK_EQ_INT((int)elfm_trace_objects_count(o), 0);
    at(&g, 1000);
    CHECK_EQ_INT((int)elfm_trace_objects_frame(o, g.p, g.f, g.v, rows), 0);
    elfm_trace_objects_free(o);
  }
  elfm_table_free(t);
  geom_free(&g);
}

static void test_from_detections(void)
{
  geom g;
  if (!geom_make(&g)) return;
  /* object A near (10, 10, 0): three flashes; B near (-20, 5, 30): two;
   * C: one dim detection (a ghost). B flashes first. */
  elfm_table *t = table("frame,t_us,x_um,y_um,z_um,intensity\n"
                        "1,2000,-20.2,5.1,30.5,150\n"
                        "3,4000,10.1,9.9,0.4,200\n"
                        "5,6000,40,40,-50,25\n"
                        "7,8000,9.8,10.2,-0.8,120\n"
                        "9,10000,-19.8,4.9,29.1,90\n"
                        "11,12000,10.3,10.0,1.0,60\n");
  elfm_error err;
  elfm_trace_objects *o = NULL;
  CHECK_OK(elfm_trace_objects_from_detections(t, 3.0, 2.0, 2, &o, &err), &err);
  if (o) {
    CHECK_EQ_INT((int)elfm_trace_objects_count(o), 2); /* C dropped */
    elfm_trace_object_info a, b;
    elfm_trace_objects_info(o, 0, &b);
    elfm_trace_objects_info(o, 1, &a);
    CHECK(b.id == 0 && a.id == 1); /* numbered by first detection: B at 2000 us */
    CHECK(b.n_points == 2 && a.n_points == 3);
    CHECK_NEAR(a.x_um, (10.1 + 9.8 + 10.3) / 3, 1e-9);
    CHECK_NEAR(b.z_um, (30.5 + 29.1) / 2, 1e-9);
    CHECK(a.first_t_us == 4000 && a.last_t_us == 12000);
    /* held everywhere, at the mean */
    elfm_trace_row rows[2];
    at(&g, 100);
    CHECK_EQ_INT((int)elfm_trace_objects_frame(o, g.p, g.f, g.v, rows), 2);
    CHECK_NEAR(rows[1].y_um, a.y_um, 1e-12);
    at(&g, 8000);
    CHECK_EQ_INT((int)elfm_trace_objects_frame(o, g.p, g.f, g.v, rows), 2);
    CHECK(rows[0].detected == 0 && rows[1].detected == 1);
    elfm_trace_objects_free(o);
  }
  /* a radius smaller than A's spread splits it (the z spread 1.8 um / kz 2) */
  CHECK_OK(elfm_trace_objects_from_detections(t, 0.3, 2.0, 1, &o, &err), &err);
  if (o) {
    CHECK_MSG(elfm_trace_objects_count(o) > 3, "%zu objects", elfm_trace_objects_count(o));
    elfm_trace_objects_free(o);
  }
  CHECK(elfm_trace_objects_from_detections(t, 0, 2.0, 1, &o, &err) != ELFM_OK);
  CHECK(elfm_trace_objects_from_detections(t, 3, 2.0, 0, &o, &err) != ELFM_OK);
  elfm_table_free(t);
  t = table("frame,t_us,x_um,y_um,z_um\n1,2000,0,0,0\n");
  CHECK(elfm_trace_objects_from_detections(t, 3, 2.0, 1, &o, &err) != ELFM_OK);
  CHECK_MSG(strstr(err.message, "intensity") != NULL, "%s", err.message);
  elfm_table_free(t);
  geom_free(&g);
}

static elfm_table *load(const char *dir, const char *name)
{
  char p[1200];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  elfm_table *t = NULL;
  elfm_error err;
  CHECK_OK(elfm_table_load_csv(p, &t, &err), &err);
  return t;
}

/* slice: every flash of every neuron against the onsets in its object's
 * trace (the first frame above `thr` after one at or below it). */
static void test_slice(const char *tmp)
{
  char dir[512], args[4096];
  snprintf(dir, sizeof dir, "%s/slice", tmp);
  elfm_error err;
  elfm_scene *s = NULL;
  if (elfm_scene_load("slice", &s, &err) || elfm_scene_set_param(s, "duration_ms=600", &err)) {
    CHECK_OK(ELFM_ERR_INVALID, &err);
    elfm_scene_free(s);
    return;
  }
  elfm_sim_options so;
  memset(&so, 0, sizeof so);
  so.write_truth = 1;
  CHECK_OK(elfm_sim_run(s, dir, &so, NULL, &err), &err);
  elfm_scene_free(s);
  snprintf(args, sizeof args, "track --calib %s/calib.json --events %s/events.raw --out %s/trk -q",
           dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args,
           "traces --calib %s/calib.json --events %s/events.raw --detections %s/trk/detections.csv "
           "--out %s/tr --quiet",
           dir, dir, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  elfm_table *truth = load(dir, "truth.csv"), *stim = load(dir, "stimulus.csv");
  elfm_table *obj = load(dir, "tr/objects.csv"), *tr = load(dir, "tr/traces.csv");
  if (!truth || !stim || !obj || !tr) goto done;
  const double thr = 20;
  int flashes = 0, found = 0, onsets = 0, neurons = 0, matched = 0;
  for (int k = 0; k < 12; k++) {
    /* neuron k: truth id k, stimulus channel k + 1 */
    double p[3] = {NAN, NAN, NAN};
    for (size_t r = 0; r < truth->n_rows; r++)
      if (elfm_table_get(truth, r, 0) == k) {
        for (int a = 0; a < 3; a++) p[a] = elfm_table_get(truth, r, 2 + a);
        break;
      }
    int nf = 0;
    for (size_t r = 0; r < stim->n_rows; r++)
      nf += elfm_table_get(stim, r, 1) == k + 1 && elfm_table_get(stim, r, 2) == 1;
    if (nf == 0) continue;
    neurons++;
    /* its object: the nearest within 2 um laterally, 4 um axially */
    int64_t id = -1;
    for (size_t r = 0; r < obj->n_rows; r++) {
      double dx = elfm_table_get(obj, r, 1) - p[0], dy = elfm_table_get(obj, r, 2) - p[1],
             dz = elfm_table_get(obj, r, 3) - p[2];
      if (dx * dx + dy * dy < 4 && fabs(dz) < 4) id = (int64_t)elfm_table_get(obj, r, 0);
    }
    flashes += nf;
    if (id < 0) continue;
    matched++;
    /* its onsets, each used once */
    int64_t on_t[256];
    int n_on = 0;
    double prev = 0;
    for (size_t r = 0; r < tr->n_rows; r++) {
      if (elfm_table_get(tr, r, 0) != id) continue;
      const double v = elfm_table_get(tr, r, 6);
      if (v > thr && prev <= thr && n_on < 256) on_t[n_on++] = (int64_t)elfm_table_get(tr, r, 2);
      prev = v;
    }
    onsets += n_on;
    for (size_t r = 0; r < stim->n_rows; r++) {
      if (elfm_table_get(stim, r, 1) != k + 1 || elfm_table_get(stim, r, 2) != 1) continue;
      const int64_t t0 = (int64_t)elfm_table_get(stim, r, 0);
      for (int i = 0; i < n_on; i++)
        if (on_t[i] >= t0 - 1500 && on_t[i] <= t0 + 2500) { /* a frame ends after the onset */
          found++;
          on_t[i] = INT64_MIN;
          break;
        }
    }
  }
  fprintf(stderr, "slice 600 ms: %d neurons flashed, %d found as objects (%zu objects); "
          "%d of %d flashes in the traces, %d onsets\n",
          neurons, matched, obj->n_rows, found, flashes, onsets);
  CHECK(neurons >= 8);
  CHECK_MSG(matched == neurons, "%d of %d neurons found", matched, neurons);
  CHECK_MSG((int)obj->n_rows <= neurons + 1, "%zu objects for %d neurons", obj->n_rows, neurons);
  CHECK_MSG(found >= flashes - 1, "%d of %d flashes", found, flashes);
  CHECK_MSG(onsets <= found + 1, "%d onsets for %d flashes found", onsets, found);
  /* every object has a row in every frame (held), 600 frames */
  CHECK_MSG(tr->n_rows == obj->n_rows * 600, "%zu rows for %zu objects", tr->n_rows, obj->n_rows);
done:
  elfm_table_free(truth);
  elfm_table_free(stim);
  elfm_table_free(obj);
  elfm_table_free(tr);
}

int main(void)
{
  test_sample();
  test_from_tracks();
  test_from_detections();
  char tmp[] = "/tmp/elfm_traces_XXXXXX";
  if (mkdtemp(tmp)) {
    test_slice(tmp);
    if (!getenv("ELFM_KEEP")) {
      char cmd[1100];
      snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
      if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
    }
  } else {
    CHECK_MSG(0, "mkdtemp failed");
  }
  return check_report();
}
