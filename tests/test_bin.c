/* test_bin.c — peaks found in a binned volume (`eventlfm track --bin-px`):
 *  - elfm_frame_bin: each output pixel the value of largest magnitude of
 *    its block (the first of equal magnitudes), listed once, the rest zero;
 *    a deep window's older pixels left out; the frame's times and counts
 *    copied; odd sizes and factor 3; a dst of another size refused; a
 *    second frame binned into the same dst leaves nothing of the first;
 *  - elfm_calib_bin: every view projects a point where the block of its
 *    full-sensor projection lies ((u - (f - 1) / 2) / f); a bead rendered
 *    on the full sensor, binned and refocused with the binned plan, peaks
 *    at its (x, y, z) um (elfm_volume_x_um of the binned volume), with
 *    144- and 61-pixel views; views binned under 3 px refused;
 *  - elfm_refocus_plane_piece: every voxel as elfm_refocus_value_at gives
 *    it, bit for bit, on pieces inside, across the volume's edges and
 *    outside it, on a plain and a deep window's frame;
 *  - elfm_peaks_refine_at on a piece of a volume: the detection
 *    elfm_peaks_detect gives in the whole volume, bit for bit, once the
 *    piece's um are moved back by the piece's place, with the caller's
 *    weak and deep_only flags kept;
 *  - elfm_recon_run with bin_px 2: each volume the binned plan's refocus
 *    of the binned frame, bit for bit, while the worker gets the full
 *    frame and the full plan; a volume plan of another calibration and a
 *    bin of 5 refused before any volume.
 * The tracker's use (the peaks refined, the accuracy) is
 * tests/track_bin.sh. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib_test_util.h"
#include "check.h"
#include "elfm_datasets.h"
#include "elfm_recon.h"
#include "elfm_tracker.h"
#include "lfm_render.h"
#include "sim_test_util.h"

static elfm_frame *frame_new(int w, int h)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(w, h, &err);
  CHECK_OK(f ? ELFM_OK : err.code, &err);
  return f;
}

/* pixels (x, y, value) into f's list in this order */
static void put(elfm_frame *f, int x, int y, float v)
{
  const uint32_t i = (uint32_t)(y * f->w + x);
  f->idx[f->nnz++] = i;
  f->data[i] = v;
  f->nnz_recent = f->nnz;
}

static void test_frame_bin(void)
{
  elfm_error err;
  elfm_frame *s = frame_new(7, 5), *d = frame_new(4, 3), *d3 = frame_new(3, 2);
  if (!s || !d || !d3) return;
  s->t_us = 1234;
  s->t_start_us = 1000;
  s->t_end_us = 2000;
  s->index = 7;
  s->n_events = 99;
  s->n_triggers = 3;
  put(s, 0, 0, 3.0f);  /* block (0, 0): 3, -5, 4: -5 */
  put(s, 1, 0, -5.0f);
  put(s, 0, 1, 4.0f);
  put(s, 2, 2, 1.0f);  /* block (1, 1): 1 then -1: the first */
  put(s, 3, 3, -1.0f);
  put(s, 6, 4, 2.0f);  /* the odd column and row: block (3, 2) */
  put(s, 4, 0, 0.0f);  /* listed but zero: its block stays unlisted */
  CHECK_OK(elfm_frame_bin(d, s, 2, &err), &err);
  const float want[12] = {-5, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 2};
  int bad = 0;
  for (int i = 0; i < 12; i++) bad += d->data[i] != want[i];
  CHECK_EQ_INT(bad, 0);
  CHECK_EQ_INT((int)d->nnz, 3);
  int listed[12] = {0};
  for (size_t i = 0; i < d->nnz; i++)
    if (d->idx[i] < 12) listed[d->idx[i]]++;
  CHECK(listed[0] == 1 && listed[5] == 1 && listed[11] == 1);
  CHECK(d->t_us == 1234 && d->t_start_us == 1000 && d->t_end_us == 2000 && d->index == 7 &&
        d->n_events == 99 && d->n_triggers == 3 && d->recent_floor == 0 && d->nnz_recent == d->nnz);
  /* factor 3: 7 x 5 -> 3 x 2; block (0, 0) holds x 0-2, y 0-2 (so the 1
   * at (2, 2) too), (1, 1) the -1 at (3, 3), (2, 1) the 2 at (6, 4) */
  CHECK_OK(elfm_frame_bin(d3, s, 3, &err), &err);
  CHECK(d3->data[0] == -5.0f && d3->data[4] == -1.0f && d3->data[5] == 2.0f && d3->nnz == 3);
  /* a dst of another size, a factor below 1 */
  CHECK(elfm_frame_bin(d3, s, 2, &err) == ELFM_ERR_INVALID);
  CHECK(elfm_frame_bin(d, s, 0, &err) == ELFM_ERR_INVALID);

  /* a deep window's frame: its pixels below the floor, and the older ones
   * listed after nnz_recent, are not the window's */
  elfm_frame_clear(s);
  put(s, 5, 1, 200.0f);
  put(s, 1, 3, 50.0f);  /* below the floor */
  put(s, 2, 0, 150.0f);
  s->recent_floor = 100.0f;
  s->nnz_recent = s->nnz;
  put(s, 6, 2, 120.0f); /* after nnz_recent: older */
  s->recent_floor = 100.0f;
  s->nnz_recent = 3;
  CHECK_OK(elfm_frame_bin(d, s, 2, &err), &err);
  const float want2[12] = {0, 150, 200, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  bad = 0;
  for (int i = 0; i < 12; i++) bad += d->data[i] != want2[i];
  CHECK_EQ_INT(bad, 0); /* and nothing of the first frame is left */
  CHECK_EQ_INT((int)d->nnz, 2);
  CHECK(d->recent_floor == 0);
  elfm_frame_free(s);
  elfm_frame_free(d);
  elfm_frame_free(d3);
}

static void test_calib_bin(const elfm_calib *c)
{
  elfm_error err;
  for (int f = 2; f <= 3; f++) {
    elfm_calib b;
    CHECK_OK(elfm_calib_bin(c, f, &b, &err), &err);
    CHECK(b.sensor_width_px == (c->sensor_width_px + f - 1) / f &&
          b.sensor_height_px == (c->sensor_height_px + f - 1) / f);
    CHECK(b.view_w_px == c->view_w_px / f && b.n_views == c->n_views);
    CHECK_NEAR(b.um_per_px, f * c->um_per_px, 1e-12);
    CHECK(b.z_min_um == c->z_min_um && b.z_step_um == c->z_step_um);
    double worst = 0;
    const double pts[3][3] = {{0, 0, 0}, {-40, 25, 60}, {33, -17, -80}};
    for (int q = 0; q < 3; q++)
      for (int v = 0; v < c->n_views; v++) {
        double u, w, ub, wb;
        elfm_calib_project(c, v, pts[q][0], pts[q][1], pts[q][2], &u, &w);
        elfm_calib_project(&b, v, pts[q][0], pts[q][1], pts[q][2], &ub, &wb);
        worst = fmax(worst, fabs(ub - (u - 0.5 * (f - 1)) / f));
        worst = fmax(worst, fabs(wb - (w - 0.5 * (f - 1)) / f));
      }
    CHECK_MSG(worst < 1e-9, "factor %d: the binned projection off by %g px", f, worst);
  }
  elfm_calib b;
  CHECK(elfm_calib_bin(c, 0, &b, &err) == ELFM_ERR_INVALID);
  CHECK(elfm_calib_bin(c, c->view_w_px / 2, &b, &err) == ELFM_ERR_INVALID);
}

/* A bead rendered on the full sensor, binned 2 x 2, refocused with the
 * binned plan: the peak at the bead's um, laterally within a quarter of
 * a binned voxel (the centroid of the 3 x 3 about the largest voxel). */
static void test_bead_binned(const elfm_calib *c)
{
  elfm_error err;
  elfm_calib b;
  CHECK_OK(elfm_calib_bin(c, 2, &b, &err), &err);
  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  elfm_refocus_plan *plan = NULL;
  CHECK_OK(elfm_refocus_plan_create(&b, &ro, &plan, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  if (plan) CHECK_OK(elfm_refocus_workspace_create(plan, &ws, &err), &err);
  elfm_volume *vol = plan ? elfm_refocus_volume_create(plan, &err) : NULL;
  elfm_frame *f = frame_new(c->sensor_width_px, c->sensor_height_px);
  elfm_frame *fb = frame_new(b.sensor_width_px, b.sensor_height_px);
  if (!plan || !ws || !vol || !f || !fb) return;
  const double bead[3][3] = {{5.3, -7.9, 10.0}, {-21.6, 14.2, -30.0}, {40.1, 2.7, 0.0}};
  for (int q = 0; q < 3; q++) {
    /* beads well inside the views (a 61-pixel view spans +-28 um) */
    if (fabs(bead[q][0]) > 0.4 * c->view_w_px * c->um_per_px) continue;
    elfm_frame_clear(f);
    render_views(f, c, bead[q][0], bead[q][1], bead[q][2], 200, 1.4, 0, 0, 0);
    CHECK_OK(elfm_frame_bin(fb, f, 2, &err), &err);
    CHECK_OK(elfm_refocus_execute(plan, fb, vol, ws, &err), &err);
    size_t at = 0;
    const size_t n = (size_t)vol->w * vol->h * vol->nz;
    for (size_t i = 1; i < n; i++)
      if (vol->data[i] > vol->data[at]) at = i;
    const int X = (int)(at % vol->w), Y = (int)(at / vol->w % vol->h), K = (int)(at / vol->w / vol->h);
    double m = 0, mx = 0, my = 0;
    for (int dy = -1; dy <= 1; dy++)
      for (int dx = -1; dx <= 1; dx++) {
        const double a = vol->data[((size_t)K * vol->h + Y + dy) * vol->w + X + dx];
        m += a;
        mx += a * dx;
        my += a * dy;
      }
    const double x_um = elfm_volume_x_um(vol, X + mx / m), y_um = elfm_volume_y_um(vol, Y + my / m);
    CHECK_MSG(fabs(x_um - bead[q][0]) < 0.25 * vol->um_per_px &&
                  fabs(y_um - bead[q][1]) < 0.25 * vol->um_per_px,
              "bead %d at (%g, %g) um, the binned peak at (%g, %g)", q, bead[q][0], bead[q][1], x_um,
              y_um);
    CHECK_MSG(fabs(elfm_volume_z_um(vol, K) - bead[q][2]) <= 2 * vol->z_step_um,
              "bead %d at z %g um, the binned peak at %g", q, bead[q][2], elfm_volume_z_um(vol, K));
  }
  elfm_frame_free(f);
  elfm_frame_free(fb);
  elfm_volume_free(vol);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(plan);
}

/* pieces against elfm_refocus_value_at, voxel by voxel */
static int piece_differs(const elfm_refocus_plan *p, const elfm_frame *f, int X0, int Y0, int w,
                         int h, int k)
{
  double piece[40 * 40];
  elfm_refocus_plane_piece(p, f, X0, Y0, w, h, k, piece);
  int bad = 0;
  for (int Y = 0; Y < h; Y++)
    for (int X = 0; X < w; X++)
      bad += piece[Y * w + X] != elfm_refocus_value_at(p, f, X0 + X, Y0 + Y, k);
  return bad;
}

static void test_plane_piece(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  elfm_refocus_plan *plan = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &ro, &plan, &err), &err);
  elfm_frame *f = frame_new(c->sensor_width_px, c->sensor_height_px);
  if (!plan || !f) return;
  render_views(f, c, 3.2, -4.1, 12.0, 180, 1.3, 0, 0, 0);
  render_views(f, c, -60.0, 55.0, -40.0, 90, 2.0, 0, 0, 0);
  int w, h, nz;
  elfm_refocus_plan_size(plan, &w, &h, &nz);
  const int at[6][5] = {{66, 64, 15, 15, 56}, {-5, -3, 15, 15, 56}, {w - 9, h - 12, 15, 15, 30},
                        {0, 0, 40, 40, 0},    {w + 2, 4, 7, 7, 10}, {20, 20, 9, 9, nz}};
  for (int q = 0; q < 6; q++)
    CHECK_MSG(piece_differs(plan, f, at[q][0], at[q][1], at[q][2], at[q][3], at[q][4]) == 0,
              "piece %d differs from the voxels' values", q);
  /* a deep window's frame: the pixels below the floor are not sampled */
  f->recent_floor = 100.0f;
  f->nnz_recent = f->nnz;
  CHECK(piece_differs(plan, f, 60, 60, 25, 25, 56) == 0);
  CHECK(piece_differs(plan, f, 20, 80, 30, 30, 20) == 0);
  elfm_frame_free(f);
  elfm_refocus_plan_free(plan);
}

/* elfm_peaks_refine_at on a piece (15 x 15 of the peak's plane and its
 * column) against elfm_peaks_detect on the whole volume */
static void test_refine_at(const elfm_calib *c)
{
  elfm_error err;
  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  elfm_refocus_plan *plan = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, &ro, &plan, &err), &err);
  elfm_refocus_workspace *ws = NULL;
  if (plan) CHECK_OK(elfm_refocus_workspace_create(plan, &ws, &err), &err);
  elfm_volume *vol = plan ? elfm_refocus_volume_create(plan, &err) : NULL;
  elfm_frame *f = frame_new(c->sensor_width_px, c->sensor_height_px);
  elfm_peaks_options po;
  elfm_peaks_options_default(&po);
  po.fit_half_z = 2;
  elfm_peaks *pk = vol ? elfm_peaks_create(&po, vol->w, vol->h, vol->nz, &err) : NULL;
  if (!plan || !ws || !vol || !f || !pk) return;
  /* the second bead near the volume's edge, so its piece is cut there */
  render_views(f, c, 7.7, -3.4, 14.0, 220, 1.3, 0, 0, 0);
  render_views(f, c, -64.5, 30.2, -20.0, 220, 1.3, 0, 0, 0);
  CHECK_OK(elfm_refocus_execute(plan, f, vol, ws, &err), &err);
  elfm_detection det[8];
  int n = 0;
  CHECK_OK(elfm_peaks_detect(pk, vol, det, 8, &n, &err), &err);
  CHECK(n >= 2);
  float buf[15 * 15 * 5];
  for (int i = 0; i < n; i++) {
    const int X = (int)lround(elfm_volume_x_vox(vol, det[i].x_um));
    const int Y = (int)lround(elfm_volume_y_vox(vol, det[i].y_um));
    const int K = (int)lround(elfm_volume_z_vox(vol, det[i].z_um));
    /* the peak's voxel: the refined position's nearest may be a
     * neighbour; the detector's is its plane's largest about it */
    int Xm = X, Ym = Y, Km = K;
    for (int k = K - 1; k <= K + 1; k++)
      for (int y = Y - 1; y <= Y + 1; y++)
        for (int x = X - 1; x <= X + 1; x++)
          if (x >= 0 && y >= 0 && k >= 0 && x < vol->w && y < vol->h && k < vol->nz &&
              vol->data[((size_t)k * vol->h + y) * vol->w + x] >
                  vol->data[((size_t)Km * vol->h + Ym) * vol->w + Xm]) {
            Xm = x;
            Ym = y;
            Km = k;
          }
    const int x0 = Xm - 7 < 0 ? 0 : Xm - 7, x1 = Xm + 8 > vol->w ? vol->w : Xm + 8;
    const int y0 = Ym - 7 < 0 ? 0 : Ym - 7, y1 = Ym + 8 > vol->h ? vol->h : Ym + 8;
    const int k0 = Km - 2 < 0 ? 0 : Km - 2, k1 = Km + 3 > vol->nz ? vol->nz : Km + 3;
    const int pw = x1 - x0, ph = y1 - y0, pn = k1 - k0;
    memset(buf, 0, sizeof buf);
    for (int k = k0; k < k1; k++)
      for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
          if (k == Km || (x == Xm && y == Ym))
            buf[((size_t)(k - k0) * ph + (y - y0)) * pw + (x - x0)] =
                vol->data[((size_t)k * vol->h + y) * vol->w + x];
    elfm_volume piece = {.w = pw, .h = ph, .nz = pn, .data = buf, .um_per_px = vol->um_per_px,
                         .z_step_um = vol->z_step_um, .frame = vol->frame, .t_us = vol->t_us};
    elfm_detection d = det[i];
    d.intensity = d.width_um = d.sigma_x_um = 0;
    d.weak = !det[i].weak; /* flags the caller's: kept */
    d.deep_only = 1;
    elfm_peaks_refine_at(pk, &piece, Xm - x0, Ym - y0, Km - k0, &d);
    d.x_um += elfm_volume_x_um(vol, Xm) - elfm_volume_x_um(&piece, Xm - x0);
    d.y_um += elfm_volume_y_um(vol, Ym) - elfm_volume_y_um(&piece, Ym - y0);
    d.z_um += elfm_volume_z_um(vol, Km) - elfm_volume_z_um(&piece, Km - k0);
    CHECK_MSG(fabs(d.x_um - det[i].x_um) < 1e-9 && fabs(d.y_um - det[i].y_um) < 1e-9 &&
                  fabs(d.z_um - det[i].z_um) < 1e-9,
              "peak %d: (%g, %g, %g) um against (%g, %g, %g)", i, d.x_um, d.y_um, d.z_um,
              det[i].x_um, det[i].y_um, det[i].z_um);
    CHECK(d.intensity == det[i].intensity && d.width_um == det[i].width_um &&
          d.sigma_x_um == det[i].sigma_x_um && d.sigma_z_um == det[i].sigma_z_um &&
          d.weak == !det[i].weak && d.deep_only == 1);
  }
  elfm_peaks_free(pk);
  elfm_frame_free(f);
  elfm_volume_free(vol);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(plan);
}

/* ---- the driver with bin_px 2 ---- */

typedef struct bin_check {
  const elfm_refocus_plan *full, *binned;
  elfm_frame *fb;
  elfm_volume *vol;
  elfm_refocus_workspace *ws;
  int n, differ, wrong_frame, wrong_plan;
} bin_check;

static elfm_status worker(const elfm_volume *v, const elfm_frame *frame,
                          const elfm_refocus_plan *plan, int slot, int thread, void *user,
                          elfm_error *err)
{
  (void)slot;
  (void)thread;
  bin_check *b = user;
  b->n++;
  b->wrong_plan += plan != b->full;
  int fw, fh, fz;
  elfm_refocus_plan_size(b->full, &fw, &fh, &fz);
  b->wrong_frame += frame->w != b->fb->w * 2;
  elfm_status st = elfm_frame_bin(b->fb, frame, 2, err);
  if (st == ELFM_OK) st = elfm_refocus_execute(b->binned, b->fb, b->vol, b->ws, err);
  if (st != ELFM_OK) return st;
  if (v->w != b->vol->w || v->h != b->vol->h || v->nz != b->vol->nz || v->w * 2 != fw) {
    b->differ++;
    return ELFM_OK;
  }
  const size_t n = (size_t)v->w * v->h * v->nz;
  b->differ += memcmp(v->data, b->vol->data, n * sizeof *v->data) != 0;
  return ELFM_OK;
}

static elfm_status count_volume(const elfm_volume *v, void *user, elfm_error *err)
{
  (void)v;
  (void)err;
  (*(int *)user)++;
  return ELFM_OK;
}

static void test_pipeline(void)
{
  char dir[] = "/tmp/elfm_bin_XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK_MSG(0, "cannot make a temporary directory");
    return;
  }
  elfm_error err;
  elfm_error_clear(&err);
  char events[700];
  elfm_calib cal, bc;
  sim_test_scene("flow", 5, dir, events, sizeof events, &cal);
  CHECK_OK(elfm_calib_bin(&cal, 2, &bc, &err), &err);
  elfm_recon_options o;
  elfm_recon_options_default(&o);
  o.threads = 1; /* the worker's scratch is one */
  bin_check b = {0};
  elfm_refocus_plan *full = NULL, *binned = NULL;
  CHECK_OK(elfm_refocus_plan_create(&cal, &o.refocus, &full, &err), &err);
  CHECK_OK(elfm_refocus_plan_create(&bc, &o.refocus, &binned, &err), &err);
  if (!full || !binned) return;
  b.full = full;
  b.binned = binned;
  b.fb = frame_new(bc.sensor_width_px, bc.sensor_height_px);
  b.vol = elfm_refocus_volume_create(binned, &err);
  CHECK_OK(elfm_refocus_workspace_create(binned, &b.ws, &err), &err);
  o.plan = full;
  o.bin_px = 2;
  o.worker = worker;
  o.worker_user = &b;
  int delivered = 0;
  /* the run's own binned plan, then the caller's */
  CHECK_OK(elfm_recon_run(events, &cal, &o, count_volume, &delivered, NULL, &err), &err);
  o.volume_plan = binned;
  CHECK_OK(elfm_recon_run(events, &cal, &o, count_volume, &delivered, NULL, &err), &err);
  CHECK(b.n >= 8 && delivered == b.n);
  CHECK_EQ_INT(b.differ, 0);
  CHECK_EQ_INT(b.wrong_frame, 0);
  CHECK_EQ_INT(b.wrong_plan, 0);
  /* the full plan as the volumes', a bin of 5: refused, no volume */
  o.volume_plan = full;
  delivered = 0;
  elfm_error_clear(&err);
  CHECK(elfm_recon_run(events, &cal, &o, count_volume, &delivered, NULL, &err) == ELFM_ERR_INVALID);
  CHECK_MSG(strstr(err.message, "another calibration") != NULL, "message: %s", err.message);
  o.volume_plan = NULL;
  o.bin_px = 5;
  elfm_error_clear(&err);
  CHECK(elfm_recon_run(events, &cal, &o, count_volume, &delivered, NULL, &err) == ELFM_ERR_INVALID);
  CHECK_MSG(strstr(err.message, "binning 5") != NULL, "message: %s", err.message);
  CHECK_EQ_INT(delivered, 0);
  elfm_frame_free(b.fb);
  elfm_volume_free(b.vol);
  elfm_refocus_workspace_free(b.ws);
  elfm_refocus_plan_free(full);
  elfm_refocus_plan_free(binned);
  char cmd[800];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

int main(void)
{
  elfm_calib c;
  test_frame_bin();
  if (calib_test_default(&c)) {
    test_calib_bin(&c);
    test_bead_binned(&c);
    /* odd views: 61 px binned to 30, whose centre is no voxel's of the 61 */
    elfm_calib odd = c;
    odd.view_w_px = odd.view_h_px = 61;
    test_bead_binned(&odd);
    test_plane_piece(&c);
    test_refine_at(&c);
  }
  test_pipeline();
  return check_report();
}
