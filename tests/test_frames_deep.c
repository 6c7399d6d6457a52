/* test_frames_deep.c — the deep window (elfm_framer_options.deep_window_us,
 * elfm_localize_options.deep_z_um):
 *  - the framer: each frame keeps its window's times, index and event
 *    count, and its pixels at or above recent_floor are exactly the plain
 *    window's, bit for bit; all its pixels are the surface of the longer
 *    window ending at the same time (a framer of windows that long, strided
 *    by the window), bit for bit; the same in any chunking;
 *  - bad options: other representations, each-trigger windows, a deep
 *    window no longer than the window;
 *  - the refocus, the view support and the occupancy read the window's
 *    pixels alone, bit for bit (a frame with older pixels takes the sparse
 *    path; the view-agreement rule refuses it); a view fit does too, unless
 *    its options ask for the older pixels and it starts beyond deep_z_um.
 * The tracker's use is tests/track_deep_window.sh. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_recon.h"
#include "frames_test_util.h"
#include "lfm_render.h"
#include "volume_test_util.h"

enum { SW = 64, SH = 48 };

/* n events over [0, span_us), time-ordered, on a few hundred pixels (so
 * that pixels fire again in later windows), from an LCG */
static void make_events(elfm_event_chunk *c, int n, int64_t span_us)
{
  uint32_t s = 12345;
  for (int i = 0; i < n; i++) {
    s = s * 1664525u + 1013904223u;
    const int x = (int)((s >> 8) % 20) + 5, y = (int)((s >> 16) % 15) + 3;
    s = s * 1664525u + 1013904223u;
    add_event(c, (int64_t)i * span_us / n, x, y, (int)((s >> 12) & 1));
  }
}

/* The frames f closes now, appended to fr[n ..] (at most max in all). */
static int take_frames(elfm_framer *f, elfm_frame **fr, int n, int max)
{
  elfm_error err;
  while (n < max) {
    fr[n] = elfm_frame_create(SW, SH, &err);
    if (!elfm_framer_next(f, fr[n])) {
      elfm_frame_free(fr[n]);
      break;
    }
    n++;
  }
  return n;
}

/* All frames of a framer with options o over the events, pushed in chunks
 * of `chunk` events; at most max frames into fr[] (created here). */
static int run_framer(const elfm_framer_options *o, const elfm_event_chunk *all, int chunk,
                      elfm_frame **fr, int max)
{
  elfm_error err;
  elfm_framer *f = NULL;
  CHECK_OK(elfm_framer_create(o, SW, SH, &f, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create((size_t)chunk, &err);
  int n = 0;
  for (size_t i = 0; i < all->n;) {
    c->n = 0;
    for (; i < all->n && c->n < (size_t)chunk; i++)
      add_event(c, all->t_us[i], all->x[i], all->y[i], all->p[i]);
    CHECK_OK(elfm_framer_push(f, c, &err), &err);
    n = take_frames(f, fr, n, max);
  }
  elfm_framer_finish(f);
  n = take_frames(f, fr, n, max);
  elfm_framer_free(f);
  elfm_chunk_free(c);
  return n;
}

static int same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static void test_framer(void)
{
  elfm_error err;
  elfm_event_chunk *all = elfm_chunk_create(6000, &err);
  make_events(all, 6000, 8000);
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.start = ELFM_START_AT_TIME;
  o.start_us = 0;
  o.polarity = ELFM_POL_ON;
  elfm_framer_options od = o, ol = o;
  od.deep_window_us = 2000;
  ol.dt_us = 2000; /* the longer windows, ending where od's do from its second on */
  ol.stride_us = 1000;
  enum { MAX = 16 };
  elfm_frame *a[MAX], *d[MAX], *d7[MAX], *l[MAX];
  const int na = run_framer(&o, all, 6000, a, MAX), nd = run_framer(&od, all, 6000, d, MAX);
  const int nd7 = run_framer(&od, all, 7, d7, MAX), nl = run_framer(&ol, all, 6000, l, MAX);
  CHECK_EQ_INT(na, 8);
  CHECK_EQ_INT(nd, na);
  CHECK_EQ_INT(nd7, na);
  CHECK(nl >= na - 1);
  int older = 0;
  for (int k = 0; k < na && k < nd; k++) {
    CHECK_EQ_INT(d[k]->t_start_us, a[k]->t_start_us);
    CHECK_EQ_INT(d[k]->t_end_us, a[k]->t_end_us);
    CHECK_EQ_INT(d[k]->t_us, a[k]->t_us);
    CHECK_EQ_INT(d[k]->index, a[k]->index);
    CHECK_EQ_INT((long long)d[k]->n_events, (long long)a[k]->n_events);
    CHECK(a[k]->recent_floor == 0.0f);
    /* 255 / e: the window's oldest event (age 1 ms at tau 1 ms) */
    CHECK_NEAR(d[k]->recent_floor, 255.0 * exp(-1.0), 1e-3);
    for (int i = 0; i < SW * SH; i++) {
      const float va = a[k]->data[i], vd = d[k]->data[i];
      if (va != 0.0f) {
        CHECK(same_bits(va, vd));
        CHECK(vd >= d[k]->recent_floor);
      } else if (vd != 0.0f) {
        CHECK(vd < d[k]->recent_floor);
        older++;
      }
      CHECK(same_bits(d7[k]->data[i], vd)); /* any chunking */
      if (k >= 1 && k - 1 < nl) CHECK(same_bits(l[k - 1]->data[i], vd));
    }
    if (k == 0) CHECK_EQ_INT(d[0]->nnz, a[0]->nnz); /* nothing before the recording */
    /* the window's pixels listed first, the older ones after them */
    CHECK_EQ_INT(d[k]->nnz_recent, a[k]->nnz);
    for (size_t i = 0; i < d[k]->nnz; i++)
      CHECK((d[k]->data[d[k]->idx[i]] >= d[k]->recent_floor) == (i < d[k]->nnz_recent));
  }
  CHECK(older > 100); /* the test holds older pixels at all */
  /* a cleared frame holds no pixel, and no floor: a frame read into it
   * afterwards (a light-field TIFF) is the window's whole */
  elfm_frame_clear(d[0]);
  CHECK(d[0]->recent_floor == 0.0f && d[0]->nnz == 0 && d[0]->nnz_recent == 0);
  for (int k = 0; k < na; k++) elfm_frame_free(a[k]);
  for (int k = 0; k < nd; k++) elfm_frame_free(d[k]);
  for (int k = 0; k < nd7; k++) elfm_frame_free(d7[k]);
  for (int k = 0; k < nl; k++) elfm_frame_free(l[k]);
  elfm_chunk_free(all);
}

static void test_bad_options(void)
{
  elfm_error err;
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.deep_window_us = 1000; /* = dt */
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "deep_window_us") != NULL);
  o.deep_window_us = 2000;
  CHECK_OK(elfm_framer_options_check(&o, &err), &err);
  o.repr = ELFM_REPR_COUNT;
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  o.repr = ELFM_REPR_EXP;
  o.polarity = ELFM_POL_SIGNED; /* negative values: no floor tells them */
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
  o.polarity = ELFM_POL_ON;
  o.start = ELFM_START_EACH_TRIGGER;
  CHECK(elfm_framer_options_check(&o, &err) == ELFM_ERR_INVALID);
}

static int same_volume_planes(const elfm_volume *x, const elfm_volume *y, int k0, int k1)
{
  const size_t pl = (size_t)x->w * x->h;
  return memcmp(x->data + (size_t)k0 * pl, y->data + (size_t)k0 * pl,
                (size_t)(k1 - k0) * pl * sizeof *x->data) == 0;
}

static int same_fit(int ra, const elfm_localize_result *a, int rb, const elfm_localize_result *b)
{
  return ra == rb && (!ra || (a->x_vox == b->x_vox && a->y_vox == b->y_vox && a->z_vox == b->z_vox &&
                              a->n_views == b->n_views && a->rms_px == b->rms_px));
}

static void test_refocus(void)
{
  elfm_error err;
  elfm_calib c;
  elfm_optics op;
  elfm_optics_default(&op);
  CHECK_OK(elfm_calib_from_optics(&op, 1280, 720, 4.86, &c, &err), &err);
  const float floor_v = (float)(255.0 * exp(-1.0));
  /* the window: a bead at 10 um (a narrow image, so that its trail shows
   * beside it), every value at or above the floor */
  elfm_frame *w = elfm_frame_create(1280, 720, &err), *old = elfm_frame_create(1280, 720, &err);
  render_views(w, &c, 5.0, -3.0, 10.0, 20.0, 0.8, 0, 0, 0);
  for (size_t i = 0; i < w->nnz; i++) w->data[w->idx[i]] += floor_v;
  /* older pixels: a bead at 70 um and the first bead's trail, below it */
  render_views(old, &c, -12.0, 8.0, 70.0, 80.0, 1.8, 0, 0, 0);
  render_views(old, &c, 3.5, -3.0, 10.0, 80.0, 1.3, 0, 0, 0);
  elfm_frame *deep = elfm_frame_create(1280, 720, &err), *whole = elfm_frame_create(1280, 720, &err);
  CHECK_OK(elfm_frame_copy(deep, w, &err), &err);
  for (size_t i = 0; i < old->nnz; i++) {
    const uint32_t pix = old->idx[i];
    if (deep->data[pix] == 0.0f) elfm_frame_set(deep, pix, fminf(old->data[pix], floor_v * 0.99f));
  }
  deep->recent_floor = floor_v;
  CHECK_OK(elfm_frame_copy(whole, deep, &err), &err);
  whole->recent_floor = 0; /* the same pixels, all of them the window's */
  CHECK(deep->nnz > w->nnz + 100);

  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  ro.agree_frac = 0;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(&c, &ro, &p, &err), &err);
  int W, H, nz;
  elfm_refocus_plan_size(p, &W, &H, &nz);
  elfm_refocus_workspace *ws = NULL;
  CHECK_OK(elfm_refocus_workspace_create(p, &ws, &err), &err);
  elfm_volume *vw = elfm_refocus_volume_create(p, &err), *vd = elfm_refocus_volume_create(p, &err);
  elfm_volume *vh = elfm_refocus_volume_create(p, &err);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, w, vw, ws, &err), &err);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, whole, vh, ws, &err), &err);
  /* auto: the deep frame takes the sparse path, and gives the window's volume */
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_AUTO, deep, vd, ws, &err), &err);
  CHECK(elfm_refocus_workspace_last_path(ws) == ELFM_PATH_SPARSE);
  CHECK(same_volume_planes(vd, vw, 0, nz));
  CHECK(!same_volume_planes(vh, vw, 0, nz)); /* the older pixels would show */
  CHECK(maxdiff(vh, vw) > 0.05f * vmax(vw));
  /* the dense path asked for (track --path dense) is the dense path, and it
   * too leaves out the older pixels: the window's volume to rounding, twice
   * in a row (its copy of the window's pixels is cleared after each use) */
  for (int rep = 0; rep < 2; rep++) {
    CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, deep, vd, ws, &err), &err);
    CHECK(elfm_refocus_workspace_last_path(ws) == ELFM_PATH_DENSE);
    CHECK(maxdiff(vd, vw) < 1e-5f * vmax(vw));
  }
  /* and the same workspace then refocuses the plain frame as ever, and a
   * deep frame with nothing in its window to an empty volume */
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, whole, vd, ws, &err), &err);
  CHECK(maxdiff(vd, vh) < 1e-5f * vmax(vh));
  elfm_frame *none = elfm_frame_create(1280, 720, &err);
  CHECK_OK(elfm_frame_copy(none, old, &err), &err);
  for (size_t i = 0; i < none->nnz; i++)
    none->data[none->idx[i]] = fminf(none->data[none->idx[i]], floor_v * 0.99f);
  none->recent_floor = floor_v;
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, deep, vd, ws, &err), &err);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_DENSE, none, vd, ws, &err), &err);
  CHECK(vmax(vd) == 0.0f);
  elfm_frame_free(none);
  /* auto takes the sparse path on a deep frame even where the fill rule
   * would take the dense one (a plan whose rule always does): track's
   * volumes stay the sparse path's */
  elfm_refocus_options rd = ro;
  rd.sparse_max_fill = 0;
  elfm_refocus_plan *pd = NULL;
  elfm_refocus_workspace *wsd = NULL;
  CHECK_OK(elfm_refocus_plan_create(&c, &rd, &pd, &err), &err);
  CHECK_OK(elfm_refocus_workspace_create(pd, &wsd, &err), &err);
  CHECK_OK(elfm_refocus_execute(pd, deep, vd, wsd, &err), &err);
  CHECK(elfm_refocus_workspace_last_path(wsd) == ELFM_PATH_SPARSE);
  CHECK(same_volume_planes(vd, vw, 0, nz));
  CHECK_OK(elfm_refocus_execute(pd, whole, vd, wsd, &err), &err);
  CHECK(elfm_refocus_workspace_last_path(wsd) == ELFM_PATH_DENSE);
  elfm_refocus_workspace_free(wsd);
  elfm_refocus_plan_free(pd);
  /* occupancy: the window's pixels */
  CHECK(elfm_refocus_occupancy(p, deep) == elfm_refocus_occupancy(p, w));
  CHECK(elfm_refocus_occupancy(p, whole) > elfm_refocus_occupancy(p, w));
  /* view support: the window's, near focus and deep */
  const elfm_calib *pc = elfm_refocus_plan_calib(p);
  const int kz10 = (int)lround((10.0 - pc->z_min_um) / pc->z_step_um);
  const int kz70 = (int)lround((70.0 - pc->z_min_um) / pc->z_step_um);
  const double X3 = 3.5 / pc->um_per_px + 0.5 * (W - 1), Y3 = -3.0 / pc->um_per_px + 0.5 * (H - 1);
  const double Xd = -12.0 / pc->um_per_px + 0.5 * (W - 1), Yd = 8.0 / pc->um_per_px + 0.5 * (H - 1);
  int nsa, nsb;
  for (int t = 0; t < 2; t++) {
    const int X = (int)lround(t ? Xd : X3), Y = (int)lround(t ? Yd : Y3), k = t ? kz70 : kz10;
    CHECK_EQ_INT(elfm_refocus_view_support(p, deep, X, Y, k, &nsa),
                 elfm_refocus_view_support(p, w, X, Y, k, &nsb));
  }
  CHECK(elfm_refocus_view_support(p, whole, (int)lround(Xd), (int)lround(Yd), kz70, &nsa) >
        elfm_refocus_view_support(p, deep, (int)lround(Xd), (int)lround(Yd), kz70, &nsb));
  /* view fits: by default the window's pixels, wherever they start */
  elfm_localize_options lo;
  elfm_localize_options_default(&lo);
  elfm_localize_result r1, r2;
  int a1 = elfm_refocus_localize(p, deep, X3, Y3, kz10, &lo, &r1);
  int a2 = elfm_refocus_localize(p, w, X3, Y3, kz10, &lo, &r2);
  CHECK(a1 && same_fit(a1, &r1, a2, &r2));
  a2 = elfm_refocus_localize(p, whole, X3, Y3, kz10, &lo, &r2);
  CHECK(!same_fit(a1, &r1, a2, &r2)); /* the trail 1.5 um behind would pull it */
  CHECK(!elfm_refocus_localize(p, deep, Xd, Yd, kz70, &lo, &r1)); /* nothing deep in the window */
  /* asked for (deep_z_um 45): a fit started deep reads every pixel, one
   * started near focus still the window's */
  lo.deep_z_um = 45;
  a1 = elfm_refocus_localize(p, deep, X3, Y3, kz10, &lo, &r1);
  a2 = elfm_refocus_localize(p, w, X3, Y3, kz10, &lo, &r2);
  CHECK(a1 && same_fit(a1, &r1, a2, &r2));
  a1 = elfm_refocus_localize(p, deep, Xd, Yd, kz70, &lo, &r1);
  a2 = elfm_refocus_localize(p, whole, Xd, Yd, kz70, &lo, &r2);
  CHECK(a1 && same_fit(a1, &r1, a2, &r2));
  /* without a deep window (floor 0) a signed frame's negative pixels count
   * as ever: the test for older pixels is a deep window's only */
  elfm_frame *sg = elfm_frame_create(1280, 720, &err);
  CHECK_OK(elfm_frame_copy(sg, w, &err), &err);
  for (size_t i = 0; i < sg->nnz; i++) sg->data[sg->idx[i]] = -sg->data[sg->idx[i]];
  CHECK(elfm_refocus_occupancy(p, sg) == elfm_refocus_occupancy(p, w));
  elfm_volume *vs = elfm_refocus_volume_create(p, &err);
  CHECK_OK(elfm_refocus_execute_path(p, ELFM_PATH_SPARSE, sg, vs, ws, &err), &err);
  float mn = 0;
  for (size_t i = 0; i < (size_t)W * H * nz; i++) mn = fminf(mn, vs->data[i]);
  CHECK(mn < -100); /* the negative images refocused, not left out */
  elfm_volume_free(vs);
  elfm_frame_free(sg);
  /* a frame copy keeps the floor (the tracker's kept frames) */
  CHECK_OK(elfm_frame_copy(whole, deep, &err), &err);
  CHECK(whole->recent_floor == deep->recent_floor);
  /* the view-agreement rule reads frames itself: it refuses them */
  elfm_refocus_plan *pa = NULL;
  elfm_refocus_options_default(&ro);
  CHECK_OK(elfm_refocus_plan_create(&c, &ro, &pa, &err), &err);
  elfm_refocus_workspace *wsa = NULL;
  CHECK_OK(elfm_refocus_workspace_create(pa, &wsa, &err), &err);
  elfm_volume *va = elfm_refocus_volume_create(pa, &err);
  CHECK(elfm_refocus_execute(pa, deep, va, wsa, &err) == ELFM_ERR_INVALID);
  CHECK(strstr(err.message, "deep window") != NULL);
  elfm_volume_free(va);
  elfm_refocus_workspace_free(wsa);
  elfm_refocus_plan_free(pa);
  elfm_volume_free(vw);
  elfm_volume_free(vd);
  elfm_volume_free(vh);
  elfm_refocus_workspace_free(ws);
  elfm_refocus_plan_free(p);
  elfm_frame_free(w);
  elfm_frame_free(old);
  elfm_frame_free(deep);
  elfm_frame_free(whole);
}

int main(void)
{
  test_framer();
  test_bad_options();
  test_refocus();
  return check_report();
}
