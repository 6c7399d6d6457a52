/* test_calib_refine.c — fitting the views' centres to data:
 *  - elfm_refocus_localize_misses: with the right centres every view's miss
 *    is ~0; a view whose images sit 0.8 px right and 0.5 px up misses by
 *    about that, the others by little; bad input gives 0;
 *  - elfm_calib_refine on synthetic frames (lfm_render.h) drawn with true
 *    centres while the fit uses centres off by up to ~2 px (and free of the
 *    two moves no data can show): three passes bring every view within
 *    0.03 px; a calibration already right moves by < 0.01 px; the
 *    collector's edges (full, NaN misses, too few points, another number of
 *    views, bad sizes); the coarse step (votes) from centres up to ~7 px
 *    off, with other objects in the frames, to within 1 px (0.45);
 *  - `eventlfm calib refine` on a simulated flow recording whose calib.json
 *    was moved the same way: the written calibration lies within 0.1 px of
 *    the simulator's (0.06 px measured: the simulated images hold a bias of
 *    that size), the true one moves by less than 0.1 px; centres up to ~7 px
 *    off come within 0.1 px with the coarse step and stay > 1 px off
 *    without it; a lens array turned 2.23 degrees is found (the search's
 *    own figure within 0.03 degree, its centres within 0.1 px, its
 *    disparities within 2e-4 px/um) and, without the turn's
 *    search, is not; a 3 x 3 array's 9 views refine at the default of
 *    agreeing views; usage errors exit 2,
 *    a missing or empty recording exits 1 naming the file;
 *  - the turn's functions (elfm_calib_turn, _turn_disparities, _turns)
 *    against elfm_calib_from_optics with the array turned. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "calib_test_util.h"
#include "check.h"
#include "cli_test_util.h"
#include "elfm_datasets.h"
#include "elfm_recon.h"
#include "lfm_render.h"

/* The largest difference of a view's disparity, px/um */
static double disparity_error(const elfm_calib *a, const elfm_calib *b)
{
  double worst = 0;
  for (int v = 0; v < a->n_views; v++)
    worst = fmax(worst, hypot(a->views[v].dx_px_per_um - b->views[v].dx_px_per_um,
                              a->views[v].dy_px_per_um - b->views[v].dy_px_per_um));
  return worst;
}

static void to_vox(const elfm_calib *c, double x, double y, double z, double q[3])
{
  q[0] = x / c->um_per_px + 0.5 * (c->view_w_px - 1);
  q[1] = y / c->um_per_px + 0.5 * (c->view_h_px - 1);
  q[2] = (z - c->z_min_um) / c->z_step_um;
}

static void test_misses(const elfm_calib *c, elfm_frame *f)
{
  elfm_error err;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, NULL, &p, &err), &err);
  if (!p) return;
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  double miss[2 * ELFM_MAX_VIEWS], wt[ELFM_MAX_VIEWS], q[3];
  elfm_localize_result r;
  const double x = 10.2, y = -7.9, z = 22.5;
  to_vox(c, x, y, z, q);
  /* the right centres: every agreeing view misses by ~0 */
  elfm_frame_clear(f);
  render_views(f, c, x, y, z, 255.0, 1.3, 0, 0, 0);
  CHECK(elfm_refocus_localize_misses(p, f, q[0] + 0.4, q[1] - 0.3, q[2] + 1, &o, &r, miss, wt));
  int agree = 0;
  double worst = 0;
  for (int v = 0; v < c->n_views; v++) {
    if (wt[v] > 0) agree++;
    worst = fmax(worst, hypot(miss[2 * v], miss[2 * v + 1]));
  }
  CHECK_MSG(agree >= 20 && agree >= r.n_views, "%d views kept (fit says %d agree)", agree, r.n_views);
  CHECK_MSG(worst < 0.03, "right centres, largest miss %.3f px", worst);
  /* view 7's images drawn 0.8 px right and 0.5 px up of where the centres
   * put them: it misses by about that (the fit takes a 1/25-ish share) */
  elfm_calib moved = *c;
  moved.views[7].cx_px += 0.8;
  moved.views[7].cy_px -= 0.5;
  elfm_frame_clear(f);
  render_views(f, &moved, x, y, z, 255.0, 1.3, 0, 0, 0);
  CHECK(elfm_refocus_localize_misses(p, f, q[0], q[1], q[2], &o, &r, miss, wt));
  CHECK_MSG(wt[7] > 0 && fabs(miss[14] - 0.8) < 0.15 && fabs(miss[15] + 0.5) < 0.15,
            "moved view misses (%.3f, %.3f), weight %g", miss[14], miss[15], wt[7]);
  worst = 0;
  for (int v = 0; v < c->n_views; v++)
    if (v != 7) worst = fmax(worst, hypot(miss[2 * v], miss[2 * v + 1]));
  CHECK_MSG(worst < 0.15, "the other views miss by up to %.3f px", worst);
  /* no arrays, no frame, no object: 0 */
  CHECK(!elfm_refocus_localize_misses(p, f, q[0], q[1], q[2], &o, &r, NULL, wt));
  CHECK(!elfm_refocus_localize_misses(p, f, q[0], q[1], q[2], &o, &r, miss, NULL));
  elfm_frame_clear(f);
  CHECK(!elfm_refocus_localize_misses(p, f, q[0], q[1], q[2], &o, &r, miss, wt));
  elfm_refocus_plan_free(p);
}

/* One pass over `n` synthetic beads drawn with `truth`, fitted with *c's
 * centres; *c moves. Returns the points collected. */
static size_t refine_pass(elfm_calib *c, const elfm_calib *truth, elfm_frame *f,
                          elfm_calib_refine *acc, int half_window, double outlier_px, uint32_t seed)
{
  elfm_error err;
  elfm_refocus_plan *p = NULL;
  CHECK_OK(elfm_refocus_plan_create(c, NULL, &p, &err), &err);
  if (!p) return 0;
  elfm_localize_options o;
  elfm_localize_options_default(&o);
  o.half_window_px = half_window;
  o.outlier_px = outlier_px;
  o.min_views = 12;
  const double fov_um = 0.5 * (c->view_w_px - 1) * c->um_per_px;
  double miss[2 * ELFM_MAX_VIEWS], wt[ELFM_MAX_VIEWS];
  for (int k = 0; k < 150; k++) {
    const double x = (2 * lcg(&seed) - 1) * (fov_um - 30), y = (2 * lcg(&seed) - 1) * (fov_um - 30);
    const double z = (2 * lcg(&seed) - 1) * 60;
    elfm_frame_clear(f);
    render_views(f, truth, x, y, z, 255.0, 1.3, 0, 0, 0);
    double q[3];
    to_vox(c, x, y, z, q);
    elfm_localize_result r;
    if (elfm_refocus_localize_misses(p, f, q[0], q[1], q[2], &o, &r, miss, wt)) {
      double at[2 * ELFM_MAX_VIEWS];
      for (int v = 0; v < c->n_views; v++) elfm_calib_project(c, v, x, y, z, &at[2 * v], &at[2 * v + 1]);
      elfm_calib_refine_add(acc, at, miss, wt);
    }
  }
  const size_t n = elfm_calib_refine_points(acc);
  double shift[2 * ELFM_MAX_VIEWS];
  int moved = -1;
  CHECK_OK(elfm_calib_refine_apply(acc, 20, c, shift, &moved, &err), &err);
  CHECK_EQ_INT(elfm_calib_refine_points(acc), 0); /* emptied for the next pass */
  CHECK_EQ_INT(moved, c->n_views);
  elfm_refocus_plan_free(p);
  return n;
}

/* The coarse step: centres off by up to ~7 px, beyond the view fit's
 * window; 150 beads vote in every view around where the wrong centres put
 * them; each view moves to its votes' peak, within 0.5 px of the truth. */
static void test_votes(const elfm_calib *truth, elfm_frame *f)
{
  elfm_error err;
  elfm_calib_refine *acc = NULL;
  CHECK_OK(elfm_calib_refine_create(truth->n_views, 10, &acc, &err), &err);
  if (!acc) return;
  CHECK(elfm_calib_refine_set_search(acc, -1, &err) == ELFM_ERR_INVALID);
  CHECK(elfm_calib_refine_set_search(acc, 65, &err) == ELFM_ERR_INVALID);
  CHECK_OK(elfm_calib_refine_set_search(acc, 12, &err), &err);
  elfm_calib c = *truth;
  perturb(&c, 4.0, 17);
  const double before = centre_error(&c, truth);
  const double fov_um = 0.5 * (c.view_w_px - 1) * c.um_per_px;
  uint32_t seed = 23;
  for (int k = 0; k < 150; k++) {
    const double x = (2 * lcg(&seed) - 1) * (fov_um - 30), y = (2 * lcg(&seed) - 1) * (fov_um - 30);
    const double z = (2 * lcg(&seed) - 1) * 60;
    elfm_frame_clear(f);
    render_views(f, truth, x, y, z, 255.0, 1.3, 0, 0, 0);
    /* other objects: two more beads the votes must not follow */
    render_views(f, truth, -x * 0.7, y * 0.5 + 9, -z, 255.0, 1.3, 0, 0, 0);
    render_views(f, truth, x * 0.3 - 11, -y, 0.5 * z, 255.0, 1.3, 0, 0, 0);
    elfm_calib_refine_vote(acc, &c, f, x, y, z);
  }
  CHECK_EQ_INT(elfm_calib_refine_votes(acc), 150);
  int moved = 0;
  CHECK_OK(elfm_calib_refine_apply_votes(acc, &c, NULL, &moved, &err), &err);
  CHECK_EQ_INT(moved, c.n_views);
  CHECK_EQ_INT(elfm_calib_refine_votes(acc), 0);
  const double after = centre_error(&c, truth);
  printf("coarse step: centres off by up to %.2f px -> %.3f px\n", before, after);
  /* within the fine passes' reach (their first window is 7 x 7 px) */
  CHECK_MSG(before > 5 && after < 1.0, "coarse step: %.2f px -> %.3f px", before, after);
  /* nothing voted: nothing moves */
  elfm_calib same = c;
  CHECK_OK(elfm_calib_refine_apply_votes(acc, &same, NULL, &moved, &err), &err);
  CHECK_EQ_INT(moved, 0);
  CHECK(same.views[4].cx_px == c.views[4].cx_px);
  /* another number of views: no vote, and an error to apply */
  elfm_calib other = c;
  other.n_views = c.n_views - 1;
  elfm_calib_refine_vote(acc, &other, f, 0, 0, 0);
  CHECK_EQ_INT(elfm_calib_refine_votes(acc), 0);
  CHECK(elfm_calib_refine_apply_votes(acc, &other, NULL, NULL, &err) == ELFM_ERR_INVALID);
  CHECK_OK(elfm_calib_refine_set_search(acc, 0, &err), &err);
  elfm_calib_refine_vote(acc, &c, f, 0, 0, 0); /* no search: ignored */
  CHECK_EQ_INT(elfm_calib_refine_votes(acc), 0);
  elfm_calib_refine_free(acc);
}

static void test_refine(const elfm_calib *truth, elfm_frame *f)
{
  elfm_error err;
  elfm_calib_refine *acc = NULL;
  CHECK_OK(elfm_calib_refine_create(truth->n_views, 1000, &acc, &err), &err);
  if (!acc) return;
  elfm_calib c = *truth;
  perturb(&c, 1.0, 5);
  const double before = centre_error(&c, truth);
  CHECK_MSG(before > 1.0, "the perturbation is too small to test (%.2f px)", before);
  double after = before;
  for (int pass = 0; pass < 3; pass++) {
    const size_t n = refine_pass(&c, truth, f, acc, pass ? 2 : 3, pass ? 1.5 : 3.0, 100 + pass);
    CHECK_MSG(n >= 100, "pass %d: only %zu of 150 beads fitted", pass, n);
    after = centre_error(&c, truth);
  }
  printf("synthetic: centres off by up to %.3f px -> %.4f px after 3 passes\n", before, after);
  CHECK_MSG(after < 0.03, "after 3 passes still %.4f px off", after);
  /* the gauge: the mean move and the move along the disparities are 0, so
   * the volume neither shifts nor refocuses (the truth's origin holds) */
  double mu = 0;
  for (int v = 0; v < c.n_views; v++) mu += c.views[v].cx_px - truth->views[v].cx_px;
  CHECK_MSG(fabs(mu / c.n_views) < 1e-9, "mean move %.3g px", mu / c.n_views);
  /* already right: moves by < 0.01 px */
  c = *truth;
  refine_pass(&c, truth, f, acc, 2, 1.5, 300);
  CHECK_MSG(centre_error(&c, truth) < 0.01, "a right calibration moved by %.4f px",
            centre_error(&c, truth));

  /* the collector's edges */
  double miss[2 * ELFM_MAX_VIEWS] = {0}, wt[ELFM_MAX_VIEWS];
  for (int v = 0; v < ELFM_MAX_VIEWS; v++) wt[v] = 1;
  miss[0] = NAN;      /* view 0's miss unusable: skipped, the others kept */
  miss[3] = INFINITY; /* view 1 too */
  for (int k = 0; k < 1000; k++) CHECK(elfm_calib_refine_add(acc, NULL, miss, wt));
  CHECK(!elfm_calib_refine_add(acc, NULL, miss, wt)); /* full */
  CHECK_EQ_INT(elfm_calib_refine_points(acc), 1000);
  c = *truth;
  int moved = 0;
  CHECK_OK(elfm_calib_refine_apply(acc, 20, &c, NULL, &moved, &err), &err);
  CHECK_EQ_INT(moved, truth->n_views - 2); /* views 0 and 1 had no usable miss */
  CHECK(c.views[0].cx_px == truth->views[0].cx_px && c.views[1].cy_px == truth->views[1].cy_px);
  elfm_calib other = *truth;
  other.n_views = truth->n_views - 1;
  CHECK(elfm_calib_refine_apply(acc, 20, &other, NULL, NULL, &err) == ELFM_ERR_INVALID);
  elfm_calib_refine_free(acc);
  acc = NULL;
  CHECK(elfm_calib_refine_create(0, 10, &acc, &err) == ELFM_ERR_INVALID && !acc);
  CHECK(elfm_calib_refine_create(ELFM_MAX_VIEWS + 1, 10, &acc, &err) == ELFM_ERR_INVALID && !acc);
  CHECK(elfm_calib_refine_create(25, 0, &acc, &err) == ELFM_ERR_INVALID && !acc);
  elfm_calib_refine_free(NULL);
}

/* The lens array's turn: elfm_calib_turn on an aligned calibration gives
 * the one from_optics builds for the turned array (the centres' mean is the
 * sensor's centre); elfm_calib_turns finds the angle back for centres and
 * disparities, also from centres moved at random besides (a turn of their
 * own of a few hundredths of a degree); turn_disparities turns those alone. */
static void test_turn(const elfm_calib *truth)
{
  elfm_optics op = truth->optics;
  op.mla_rotation_deg = 2.5;
  elfm_calib want, t = *truth;
  elfm_error err;
  CHECK_OK(elfm_calib_from_optics(&op, truth->sensor_width_px, truth->sensor_height_px, truth->pixel_um,
                                  &want, &err), &err);
  elfm_calib_turn(&t, 2.5);
  double worst_c = 0, worst_d = 0;
  for (int v = 0; v < t.n_views; v++) {
    worst_c = fmax(worst_c, hypot(t.views[v].cx_px - want.views[v].cx_px, t.views[v].cy_px - want.views[v].cy_px));
    worst_d = fmax(worst_d, hypot(t.views[v].dx_px_per_um - want.views[v].dx_px_per_um,
                                  t.views[v].dy_px_per_um - want.views[v].dy_px_per_um));
  }
  CHECK_MSG(worst_c < 1e-9 && worst_d < 1e-12, "turned: centres %.3g px, disparities %.3g px/um off", worst_c,
            worst_d);
  CHECK_NEAR(t.optics.mla_rotation_deg, 2.5, 1e-12);
  double tc, td;
  elfm_calib_turns(truth, &tc, &td);
  CHECK(fabs(tc) < 1e-9 && fabs(td) < 1e-9);
  elfm_calib_turns(&t, &tc, &td);
  CHECK_NEAR(tc, 2.5, 1e-9);
  CHECK_NEAR(td, 2.5, 1e-9);
  elfm_calib m = t;
  perturb(&m, 0.5, 77); /* lenslets placed 0.5 px RMS off: barely a turn */
  elfm_calib_turns(&m, &tc, &td);
  CHECK_NEAR(tc, 2.5, 0.05);
  CHECK_NEAR(td, 2.5, 1e-9);
  elfm_calib d = t;
  elfm_calib_turn_disparities(&d, -3.0);
  elfm_calib_turns(&d, &tc, &td);
  CHECK(d.views[0].cx_px == t.views[0].cx_px);
  CHECK_NEAR(tc, 2.5, 1e-9);
  CHECK_NEAR(td, -0.5, 1e-9);
  CHECK_NEAR(d.optics.mla_rotation_deg, -0.5, 1e-12);
  /* the optics' angle stays within the file's -45..45 */
  elfm_calib far = *truth;
  far.optics.mla_rotation_deg = 44;
  elfm_calib_turn_disparities(&far, 3.0);
  CHECK_NEAR(far.optics.mla_rotation_deg, -43.0, 1e-12);
  elfm_calib few = *truth;
  few.n_views = 1; /* view (-2, -2) alone: its centre is the mean */
  elfm_calib_turns(&few, &tc, &td);
  CHECK(tc == 0.0 && fabs(td) < 1e-9);
}

static char dir[] = "/tmp/elfm_calib_refine_XXXXXX";

static int run(const char *args) { return cli_run(dir, args); }
static int err_has(const char *text) { return cli_file_has(dir, "err.txt", text); }

/* The turn calib refine's search printed ("the lens array's turn: +2.23
 * deg (the sharpest ..."), NAN when none: the search's own figure, which
 * the centres' fit after it may correct. */
static double searched_turn_deg(void)
{
  char buf[8192];
  if (!cli_read_file(dir, "err.txt", buf, sizeof buf)) return NAN;
  const char *key = "the lens array's turn: ";
  for (const char *at = strstr(buf, key); at; at = strstr(at + 1, key)) {
    const char *v = at + strlen(key);
    if (*v == '+' || *v == '-') return strtod(v, NULL);
  }
  return NAN;
}

/* `eventlfm calib refine --calib CALIB --events SIM/events.raw --out
 * DIR/OUT EXTRA`; exit 0 and *r the calibration it wrote, checked. */
static void refine_cli(const char *calib, const char *sim, const char *out, const char *extra,
                       elfm_calib *r)
{
  char args[3000], q[800];
  elfm_error err;
  snprintf(args, sizeof args, "calib refine --calib %s --events %s/events.raw --out %s/%s %s", calib,
           sim, dir, out, extra);
  CHECK_EQ_INT(run(args), 0);
  snprintf(q, sizeof q, "%s/%s", dir, out);
  CHECK_OK(elfm_calib_load(q, r, &err), &err);
}

/* The flow scene with the n `key=value` kv simulated into DIR/name (its
 * path into out), and its calibration into *truth; 0 when that failed
 * (counted by the checks) */
static int sim_flow(const char *name, const char *const *kv, int n, char *out, size_t cap,
                    elfm_calib *truth)
{
  elfm_error err;
  elfm_scene *sc = NULL;
  CHECK_OK(elfm_scene_load("flow", &sc, &err), &err);
  if (!sc) return 0;
  elfm_status st = elfm_scene_set_params(sc, kv, n, &err);
  CHECK_OK(st, &err);
  snprintf(out, cap, "%s/%s", dir, name);
  elfm_sim_options so = {.progress = NULL, .progress_user = NULL, .write_truth = 0};
  if (st == ELFM_OK) {
    st = elfm_sim_run(sc, out, &so, NULL, &err);
    CHECK_OK(st, &err);
  }
  elfm_scene_free(sc);
  char p[800];
  snprintf(p, sizeof p, "%s/calib.json", out);
  if (st == ELFM_OK) {
    st = elfm_calib_load(p, truth, &err);
    CHECK_OK(st, &err);
  }
  return st == ELFM_OK;
}

static void test_cli(void)
{
  if (!cli_test_ready(dir)) return;
  elfm_error err;
  char sim[700], p[800], q[800], args[3000];
  elfm_calib truth, c;
  const char *kv60[] = {"duration_ms=60"};
  if (!sim_flow("sim", kv60, 1, sim, sizeof sim, &truth)) return;
  c = truth;
  perturb(&c, 1.0, 9);
  snprintf(p, sizeof p, "%s/moved.json", dir);
  CHECK_OK(elfm_calib_save(&c, p, &err), &err);

  char moved[800], far_path[800];
  snprintf(moved, sizeof moved, "%s", p);
  elfm_calib r;
  refine_cli(moved, sim, "r.json", "--ms 60", &r);
  CHECK(err_has("pass 4") && err_has("view (+2, +2)")); /* progress and the moves on stderr */
  const double before = centre_error(&c, &truth), after = centre_error(&r, &truth);
  printf("simulated flow, 60 ms: centres off by up to %.3f px -> %.4f px\n", before, after);
  CHECK_MSG(before > 1.0 && after < 0.1, "refined centres off by %.3f px (%.3f before)", after, before);
  /* the disparities turn to the fitted centres' grid: here by no more than
   * the centres' few hundredths of a pixel make (2e-4 px/um: 0.03 deg),
   * not by the turn hidden in the moved centres (~0.04 deg) */
  CHECK(r.z_step_um == truth.z_step_um);
  CHECK_MSG(disparity_error(&r, &truth) < 2e-4, "disparities moved by %.3g px/um", disparity_error(&r, &truth));
  /* the simulator's own calibration stays */
  snprintf(q, sizeof q, "%s/calib.json", sim);
  refine_cli(q, sim, "t.json", "--ms 60 --passes 2 --turn-deg 0 --quiet", &r);
  CHECK_MSG(centre_error(&r, &truth) < 0.1, "the right calibration moved by %.3f px",
            centre_error(&r, &truth));

  /* centres ~4 px RMS off (up to ~7 px, beyond the view fit's window): the
   * coarse step brings them in; without it (--search-px 0) they stay off */
  elfm_calib far = truth;
  perturb(&far, 4.0, 31);
  snprintf(far_path, sizeof far_path, "%s/far.json", dir);
  CHECK_OK(elfm_calib_save(&far, far_path, &err), &err);
  refine_cli(far_path, sim, "f.json", "--ms 60 --turn-deg 0", &r);
  CHECK(err_has("coarse step"));
  const double far_after = centre_error(&r, &truth);
  refine_cli(far_path, sim, "f0.json", "--ms 60 --search-px 0 --turn-deg 0 --quiet", &r);
  const double far_fine_only = centre_error(&r, &truth);
  printf("simulated flow, centres up to %.2f px off: %.4f px with the coarse step, %.3f px without\n",
         centre_error(&far, &truth), far_after, far_fine_only);
  CHECK_MSG(centre_error(&far, &truth) > 5 && far_after < 0.1, "far off: %.3f px after refining", far_after);
  CHECK_MSG(far_fine_only > 1, "without the coarse step the far-off centres came in (%.3f px): the test "
            "no longer shows what the step is for", far_fine_only);
  /* A lens array turned 2.23 degrees against the sensor's rows (the outer
   * views' centres 5-15 px from the aligned array's, their disparities
   * turned): the search finds the turn, the passes the centres, and the
   * disparities turn with them. The turn lies between the search's steps
   * of 0.1 degree, so its own figure comes from the parabola through the
   * sharpest step and its neighbours: within 0.03 degree (2.23 measured;
   * 2.17 with the vertex on the wrong side, which the centres' fit after it
   * hid). Without the search (--turn-deg 0) the centres stay off, or no
   * point is fitted at all. */
  {
    char sim2[760];
    elfm_calib truth2;
    const char *kv[] = {"duration_ms=60", "optics.mla_rotation_deg=2.23"};
    if (sim_flow("sim_turned", kv, 2, sim2, sizeof sim2, &truth2)) {
      CHECK(truth2.optics.mla_rotation_deg == 2.23);
      snprintf(q, sizeof q, "%s/calib.json", sim); /* the aligned array's */
      refine_cli(q, sim2, "turned.json", "--ms 60", &r);
      const double searched = searched_turn_deg();
      const double ce = centre_error(&r, &truth2), de = disparity_error(&r, &truth2);
      printf("simulated flow, lens array turned 2.23 deg: the search %.2f deg, found %.3f deg, centres "
             "%.4f px and disparities %.2g px/um off (before: %.2f px, %.3g px/um)\n", searched,
             r.optics.mla_rotation_deg, ce, de, centre_error(&truth, &truth2), disparity_error(&truth, &truth2));
      CHECK_MSG(fabs(searched - 2.23) <= 0.03, "the search printed %.2f deg for a turn of 2.23", searched);
      CHECK_NEAR(r.optics.mla_rotation_deg, 2.23, 0.05);
      CHECK_MSG(ce < 0.1 && de < 2e-4, "turned array: centres %.3f px, disparities %.3g px/um off", ce, de);
      snprintf(args, sizeof args, "calib refine --calib %s --events %s/events.raw --out %s/turned0.json --ms 60 "
               "--turn-deg 0 --quiet", q, sim2, dir);
      if (run(args) == 0) {
        snprintf(p, sizeof p, "%s/turned0.json", dir);
        CHECK_OK(elfm_calib_load(p, &r, &err), &err);
        CHECK_MSG(centre_error(&r, &truth2) > 1, "without the search the turned array's centres came in "
                  "(%.3f px): the test no longer shows what the search is for", centre_error(&r, &truth2));
      }
    }
  }
  /* A 3 x 3 lens array: 9 views, where the default of 12 agreeing views
   * could fit no point; it scales to 5 (12 of 25) */
  {
    char sim3[760];
    elfm_calib truth3, moved3;
    const char *kv[] = {"duration_ms=40", "optics.lenslets_per_side=3"};
    if (sim_flow("sim3", kv, 2, sim3, sizeof sim3, &truth3)) {
      CHECK_EQ_INT(truth3.n_views, 9);
      moved3 = truth3;
      perturb(&moved3, 1.0, 5);
      snprintf(p, sizeof p, "%s/moved3.json", dir);
      CHECK_OK(elfm_calib_save(&moved3, p, &err), &err);
      refine_cli(p, sim3, "r3.json", "--ms 40 --turn-deg 0 --quiet", &r);
      printf("simulated flow, 3 x 3 views: centres off by up to %.3f px -> %.4f px\n",
             centre_error(&moved3, &truth3), centre_error(&r, &truth3));
      CHECK_MSG(centre_error(&moved3, &truth3) > 0.5 && centre_error(&r, &truth3) < 0.1,
                "3 x 3: refined centres %.3f px off", centre_error(&r, &truth3));
      /* more agreeing views asked for than the calibration has: a usage error naming it */
      snprintf(args, sizeof args, "calib refine --calib %s --events %s/events.raw --out %s/u.json --min-views 10",
               p, sim3, dir);
      CHECK_EQ_INT(run(args), 2);
      CHECK(err_has("9 views"));
    }
  }
  /* a later stretch (--from-us) or a shorter one (--to-us) works as well */
  refine_cli(moved, sim, "w.json", "--from-us 20000 --to-us 60000 --turn-deg 0 --quiet", &r);
  CHECK_MSG(centre_error(&r, &truth) < 0.1, "refined on 20-60 ms: %.3f px", centre_error(&r, &truth));
  /* coarser planes for the passes: the file written keeps its own */
  refine_cli(moved, sim, "z.json", "--ms 30 --passes 1 --z-step-um 4 --turn-deg 0 --quiet", &r);
  CHECK(r.z_step_um == truth.z_step_um && r.z_min_um == truth.z_min_um);
  CHECK_MSG(centre_error(&r, &truth) < 0.5 * centre_error(&c, &truth), "one pass on 4 um planes: %.3f px",
            centre_error(&r, &truth));
  /* usage errors: exit 2 */
  CHECK_EQ_INT(run("calib refine"), 2);
  const char *bad[] = {"--passes -1", "--passes 21", "--passes 2.5", "--sweep-um-per-ms 0",
                       "--sweep-um-per-ms -1", "--ms 0", "--min-views 2", "--threshold -1",
                       "--from-us 50 --to-us 40", "--dt-us 10", "--bogus", "--z-min-um 500", "--search-px 65",
                       "--turn-deg 46", "--turn-deg -1", "--turn-deg x"};
  for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
    snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/events.raw --out %s/u.json %s",
             sim, sim, dir, bad[k]);
    CHECK_MSG(run(args) == 2, "%s: not a usage error", bad[k]);
  }
  /* failures: exit 1 naming the file; nothing written */
  snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/none.raw --out %s/u.json", sim, dir, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(err_has("none.raw"));
  snprintf(p, sizeof p, "%s/empty.csv", dir);
  FILE *fe = fopen(p, "w");
  if (fe) {
    fputs("t_us,x,y,p\n", fe);
    fclose(fe);
  }
  snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/empty.csv --out %s/u.json --quiet", sim, dir, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(err_has("empty.csv") && err_has("no events"));
  /* bright points nowhere (threshold above any peak): exit 1 saying so */
  snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/events.raw --out %s/u.json --ms 5 --threshold 1e6 --quiet",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(err_has("no point"));
  /* --from-us, --to-us: the passes read that stretch. Past the last
   * event nothing can be fitted, and the message names the stretch */
  snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/events.raw --out %s/u.json --from-us 90000 --turn-deg 0 --quiet",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(err_has("90000..290000 us"));
  snprintf(args, sizeof args, "calib refine --calib %s/calib.json --events %s/events.raw --out %s/u.json --to-us 500 --turn-deg 0 --quiet",
           sim, sim, dir);
  CHECK_EQ_INT(run(args), 1);
  CHECK(err_has("..500 us"));
  snprintf(p, sizeof p, "%s/u.json", dir);
  CHECK_MSG(access(p, F_OK) != 0, "a failed refine wrote %s", p);

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

int main(void)
{
  elfm_calib c;
  elfm_error err;
  if (!calib_test_default(&c)) return check_report();
  elfm_frame *f = elfm_frame_create(c.sensor_width_px, c.sensor_height_px, &err);
  CHECK(f != NULL);
  if (!f) return check_report();
  test_misses(&c, f);
  test_refine(&c, f);
  test_votes(&c, f);
  test_turn(&c);
  elfm_frame_free(f);
  test_cli();
  return check_report();
}
