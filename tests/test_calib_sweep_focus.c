/* test_calib_sweep_focus.c — the focal plane from a z sweep
 * (elfm_calib_sweep_fit.focus_um, recon/calib_sweep.c; elfm_calib_move_focus,
 * elfm_calib_grid_pitch, elfm_calib_scale_relay; `calib refine --sweep`,
 * --keep-focal-plane and --keep-scale, cli/cmd_calib_sweep.c):
 *  - frames drawn by hand: one bead swept from z -80 to +80 um whose images
 *    are brightest at a focus of +12 um (or -30), fainter away from it, from
 *    centres ~5 px off (none of it in proportion to the disparities): the
 *    focus found within 1 um; images as bright at every depth, brightest at
 *    the sweep's end (+100 um) or not below half that on one side (+70 um):
 *    no focus (NaN); nor for a faint bead whose images are only 3.3 times
 *    stronger in focus than far from it; one way, no way's own; up in 200
 *    frames brightest at
 *    +20 and down in 100 brightest at +4: each way's within 1-1.5 um, the
 *    focus their mean, 12, within 1;
 *  - elfm_calib_move_focus: every point's images kept at z less the move,
 *    to 1e-9 px; NaN or infinite moves nothing; elfm_calib_grid_pitch: the
 *    optics' 600 um x 1.25 / 4.86 um, NaN on three views in a row;
 *    elfm_calib_scale_relay: the scale and disparities x k, the pitch kept,
 *    0, negative or NaN nothing;
 *  - the command on zsweep seed 1 with a relay 2.4 % longer than the
 *    optics' calibration's (whose focal plane then lies 20.9 um off): the
 *    one-way sweep read forwards and backwards (recon/events_reverse.c;
 *    its reversed copy in TMPDIR, removed after), whose foci lean apart
 *    by more than 1 um, the focal plane moved to their mean (said, as are
 *    both), within 1.2 um of the truth's (+0.55 measured; the fit's own
 *    +1.91, taken when TMPDIR cannot be written, and said), and then the
 *    views' grid, 1.02 x the start's, taken for the relay's magnification:
 *    um_per_px and the disparities within 0.15 % of the truth's (-0.06 /
 *    +0.06 % measured; -0.21 / +0.21 % from the fit's own focus; the
 *    optics' +2.40 / -2.34 %), the messages say so; --keep-scale keeps the
 *    optics' scale (the same focal plane); the piezo's speed given, the
 *    disparities follow it (within 1 %, -0.68 %) and um_per_px the grid;
 *    --keep-focal-plane keeps it 15 um or more off and says nothing of the
 *    grid; the bead swept up and down (1.8 s): each way's focus, not read
 *    backwards, their mean within 0.7 um (+0.39); one way at 0.4 mm/s, read
 *    both ways on the integral started empty, within 1.2 um (+0.59; 3.85
 *    with its start levels), also as a CSV of the events left of x = 1200
 *    (no geometry: the reversed copy gets the sensor's); under 10 Hz of
 *    sensor noise a pixel (at 0.4 mm/s), taken for several objects, read
 *    again through the 3 x 3 median (said) and fitted within 1.2 um
 *    (-0.71), refused with --median 0; under 8 Hz read both ways (the
 *    backward reading through the median) within 1.2 um (+0.14); --repr
 *    exp refused, the integral named; with the
 *    optics' own relay (focus found
 *    within the 2 um a sweep tells) the start's focal plane and scale are
 *    kept, within 0.5 um of the truth's;
 *  - a flow (100 ms, seed 2) under the same relay, tracked with those
 *    calibrations: alpha 0.85 or more with the focal plane and the scale
 *    moved (0.893 measured, 0.811 with the fit's own focus; 0.898 with
 *    the simulator's own calibration), 0.70 or more and less than that
 *    with the scale kept (0.781), under 0.1
 *    with the focal plane kept (0.004). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "calib_test_util.h"
#include "check.h"
#include "cli_test_util.h"
#include "elfm_recon.h"

#define N_FRAMES 200
#define WIDTH_UM 25.0

/* The offset, um, of a's focal plane in b's depths: a's centres as b's
 * moved by a constant per axis and by b's disparities x the offset (least
 * squares over both axes; elfm_calib_move_focus(b, z) gives z) */
static double focal_offset(const elfm_calib *a, const elfm_calib *b)
{
  /* unknowns: cx, cy, z; rows: each view's two axes */
  double m[3][4] = {{0}};
  for (int v = 0; v < a->n_views; v++)
    for (int axis = 0; axis < 2; axis++) {
      const double x[3] = {axis == 0, axis == 1, axis ? b->views[v].dy_px_per_um : b->views[v].dx_px_per_um};
      const double y = axis ? a->views[v].cy_px - b->views[v].cy_px : a->views[v].cx_px - b->views[v].cx_px;
      for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) m[r][c] += x[r] * x[c];
        m[r][3] += x[r] * y;
      }
    }
  /* the two constants eliminated: z = (Sdy - Sd Sy / n) / (Sdd - Sd^2 / n) per axis, pooled */
  const double n = a->n_views;
  const double num = m[2][3] - m[0][2] * m[0][3] / n - m[1][2] * m[1][3] / n;
  const double den = m[2][2] - m[0][2] * m[0][2] / n - m[1][2] * m[1][2] / n;
  return num / den;
}

/* A frame of the bead at (5, -3) um and depth z, its image's peak
 * 60 x (floor + (1 - floor) exp(-((z - focus) / WIDTH_UM)^2)), or 60 with
 * focus NaN, in every view, and noise */
static double floor_frac = 0.05;
static void draw(elfm_frame *f, const elfm_calib *truth, double z, double focus_um, uint32_t *seed)
{
  elfm_frame_clear(f);
  const double e = (z - focus_um) / WIDTH_UM;
  const double peak = isnan(focus_um) ? 60 : 60 * (floor_frac + (1 - floor_frac) * exp(-e * e));
  for (int v = 0; v < truth->n_views; v++) {
    double u, w;
    elfm_calib_project(truth, v, 5, -3, z, &u, &w);
    frame_spot(f, u, w, peak);
  }
  for (int n = 0; n < 400; n++)
    frame_put(f, (long)(lcg(seed) * (f->w - 1)), (long)(lcg(seed) * (f->h - 1)), (float)(1 + 3 * lcg(seed)));
}

/* The sweep's fit from centres ~5 px off (gauge-free: the fitted depths
 * are the truth's): N_FRAMES frames 1 ms apart from z -80 to +80 um, the
 * images brightest at focus_um; then, with n_down > 0, n_down frames back
 * to -80, brightest at down_um. The views moved into *moved. */
static elfm_calib_sweep_fit sweep_fit(const elfm_calib *truth, elfm_frame *f, double focus_um, int n_down,
                                      double down_um, int *moved)
{
  elfm_error err;
  elfm_calib_sweep_fit fit = {.focus_um = NAN};
  elfm_calib c = *truth;
  perturb(&c, 5, 21);
  elfm_calib_sweep *s = NULL;
  CHECK_OK(elfm_calib_sweep_create(&c, N_FRAMES + (size_t)n_down, &s, &err), &err);
  if (!s) return fit;
  uint32_t seed = 7;
  static elfm_calib_sweep_image img;
  for (int k = 0; k < N_FRAMES + n_down; k++) {
    const int up = k < N_FRAMES;
    const double z = up ? -80 + 160.0 * k / (N_FRAMES - 1) : 80 - 160.0 * (k - N_FRAMES + 1) / n_down;
    draw(f, truth, z, up ? focus_um : down_um, &seed);
    CHECK_OK(elfm_calib_sweep_spots(s, f, &img, &err), &err);
    CHECK(elfm_calib_sweep_add(s, 1000 * (int64_t)k, &img));
  }
  *moved = -1;
  CHECK_OK(elfm_calib_sweep_apply(s, 20, &c, NULL, moved, &err), &err);
  elfm_calib_sweep_result(s, &fit);
  elfm_calib_sweep_free(s);
  return fit;
}

static void test_by_hand(const elfm_calib *truth)
{
  elfm_error err;
  elfm_frame *f = elfm_frame_create(truth->sensor_width_px, truth->sensor_height_px, &err);
  CHECK(f != NULL);
  if (!f) return;
  const double at[2] = {12, -30};
  for (int k = 0; k < 2; k++) {
    int moved;
    const elfm_calib_sweep_fit fit = sweep_fit(truth, f, at[k], 0, NAN, &moved);
    printf("a bead brightest at z %+.0f um: the sweep's focus %+.3f um (%d views moved)\n", at[k], fit.focus_um,
           moved);
    CHECK_EQ_INT(moved, truth->n_views - 1);
    CHECK_MSG(fabs(fit.focus_um - at[k]) < 1, "brightest at %g um, the focus found at %.3f", at[k], fit.focus_um);
    CHECK(isnan(fit.focus_up_um) && isnan(fit.focus_down_um)); /* one way */
  }
  /* no depth where the images are brightest, or no fall below half the
   * peak beyond it: no focus */
  const double none[3] = {NAN, 100, 70};
  int moved;
  for (int k = 0; k < 3; k++) {
    const double z = sweep_fit(truth, f, none[k], 0, NAN, &moved).focus_um;
    printf("a bead brightest at %g: the sweep's focus %g (%d views moved)\n", none[k], z, moved);
    CHECK_EQ_INT(moved, truth->n_views - 1);
    CHECK_MSG(isnan(z), "brightest at %g um, a focus found at %.3f", none[k], z);
  }
  /* a faint bead's images, 3.3 times stronger in focus than far from it
   * (a simulated one rose 3.7 times, a bright one 25-36): no focus */
  floor_frac = 0.3;
  const double faint = sweep_fit(truth, f, 12, 0, NAN, &moved).focus_um;
  floor_frac = 0.05;
  printf("a faint bead brightest at +12: the sweep's focus %g\n", faint);
  CHECK_MSG(isnan(faint), "a faint bead: a focus at %.3f", faint);
  /* up in 200 frames, brightest at +20, and down in 100, brightest at +4
   * (a bead's images lead it into focus): each way's own, and their mean,
   * 12, where the frames fitted together (two going up for one coming
   * down) would lean to the way up */
  const elfm_calib_sweep_fit two = sweep_fit(truth, f, 20, 100, 4, &moved);
  printf("up brightest at +20, down at +4: the focus %+.3f um (up %+.3f, down %+.3f)\n", two.focus_um,
         two.focus_up_um, two.focus_down_um);
  CHECK_MSG(fabs(two.focus_up_um - 20) < 1 && fabs(two.focus_down_um - 4) < 1.5 && fabs(two.focus_um - 12) < 1,
            "up and down: the focus %.3f (up %.3f, down %.3f)", two.focus_um, two.focus_up_um, two.focus_down_um);
  elfm_frame_free(f);
}

static void test_move(const elfm_calib *truth)
{
  elfm_calib c = *truth;
  elfm_calib_move_focus(&c, 17.5);
  CHECK_MSG(fabs(focal_offset(&c, truth) - 17.5) < 1e-9, "the focal plane moved by %.6f um",
            focal_offset(&c, truth));
  double worst = 0;
  for (int v = 0; v < truth->n_views; v++) {
    double u0, w0, u1, w1;
    elfm_calib_project(truth, v, 20, -11, 33, &u0, &w0);
    elfm_calib_project(&c, v, 20, -11, 33 - 17.5, &u1, &w1);
    worst = fmax(worst, hypot(u1 - u0, w1 - w0));
  }
  CHECK_MSG(worst < 1e-9, "images %.3g px apart after the focal plane's move", worst);
  c = *truth;
  elfm_calib_move_focus(&c, NAN);
  elfm_calib_move_focus(&c, INFINITY);
  CHECK(memcmp(&c, truth, sizeof c) == 0);

  /* the grid's pitch: the lenslets' 600 um x the relay's 1.25 over 4.86
   * um pixels; a relay 3 % longer: the lateral scale and the disparities
   * 3 % more px per um, the centres (and the pitch) as they were */
  const double pitch = elfm_calib_grid_pitch(truth);
  printf("the grid's pitch %.4f px\n", pitch);
  CHECK_MSG(fabs(pitch - 600 * 1.25 / 4.86) < 0.01, "the grid's pitch %.4f px", pitch);
  elfm_calib_scale_relay(&c, 1.03);
  CHECK(fabs(elfm_calib_grid_pitch(&c) - pitch) < 1e-9);
  CHECK(fabs(c.um_per_px * 1.03 - truth->um_per_px) < 1e-12 &&
        fabs(c.views[0].dx_px_per_um - 1.03 * truth->views[0].dx_px_per_um) < 1e-12 &&
        fabs(c.views[0].dy_px_per_um - 1.03 * truth->views[0].dy_px_per_um) < 1e-12);
  CHECK(!truth->has_optics || fabs(c.optics.relay - 1.03 * truth->optics.relay) < 1e-12);
  c = *truth;
  elfm_calib_scale_relay(&c, 0);
  elfm_calib_scale_relay(&c, -1);
  elfm_calib_scale_relay(&c, NAN);
  CHECK(memcmp(&c, truth, sizeof c) == 0);
  /* three views in a row span no grid */
  elfm_calib row = *truth;
  row.n_views = 0;
  for (int v = 0; v < truth->n_views; v++)
    if (truth->views[v].j == 0 && abs(truth->views[v].i) <= 1) row.views[row.n_views++] = truth->views[v];
  CHECK_EQ_INT(row.n_views, 3);
  CHECK(isnan(elfm_calib_grid_pitch(&row)));
}

static char dir[] = "/tmp/elfm_calib_focus_XXXXXX";

/* simulate zsweep --seed 1 PARAMS into DIR/NAME (no truth) */
static void sweep_sim(const char *name, const char *params)
{
  char args[3000];
  snprintf(args, sizeof args, "simulate zsweep --seed 1 %s --out %s/%s --no-truth --quiet", params, dir, name);
  CHECK_EQ_INT(cli_run(dir, args), 0);
}

/* calib refine --sweep --passes 0 on DIR/EVENTS with the optics'
 * calibration, into DIR/OUT, extra options EXTRA; its exit code CHECKed
 * to be rc */
static void refine_run(const char *events, const char *out, const char *extra, int rc)
{
  char args[3000];
  snprintf(args, sizeof args, "calib refine --sweep --calib %s/optics.json --events %s/%s --out %s/%s --passes 0 %s",
           dir, dir, events, dir, out, extra);
  CHECK_EQ_INT(cli_run(dir, args), rc);
}

/* refine_run on zsweep DIR/NAME, expected to succeed, into DIR/OUT (and
 * *r); its focal plane's offset from the simulator's calibration (into
 * *truth), um (NaN when it failed) */
static double refine(const char *name, const char *out, const char *extra, elfm_calib *r, elfm_calib *truth)
{
  char ev[800], p[800];
  elfm_error err;
  snprintf(ev, sizeof ev, "%s/events.raw", name);
  refine_run(ev, out, extra, 0);
  snprintf(p, sizeof p, "%s/%s/calib.json", dir, name);
  CHECK_OK(elfm_calib_load(p, truth, &err), &err);
  snprintf(p, sizeof p, "%s/%s", dir, out);
  if (elfm_calib_load(p, r, &err) != ELFM_OK) return NAN;
  return focal_offset(r, truth);
}

/* a's lateral scale and corner view's disparity against b's, less 1 */
static double scale_off(const elfm_calib *a, const elfm_calib *b)
{
  return a->um_per_px / b->um_per_px - 1;
}
static double disparity_off(const elfm_calib *a, const elfm_calib *b)
{
  return a->views[0].dx_px_per_um / b->views[0].dx_px_per_um - 1;
}

/* DIR/in's events with x < x_max into DIR/out as CSV (t_us,x,y,p: no
 * geometry) */
static void write_roi_csv(const char *in, const char *out, int x_max)
{
  char a[800], b[800];
  elfm_error err;
  snprintf(a, sizeof a, "%s/%s", dir, in);
  snprintf(b, sizeof b, "%s/%s", dir, out);
  elfm_reader *r = NULL;
  elfm_writer *w = NULL;
  elfm_event_chunk *c = elfm_chunk_create(65536, &err);
  CHECK(c != NULL);
  CHECK_OK(elfm_reader_open(a, NULL, &r, &err), &err);
  CHECK_OK(elfm_writer_open(b, ELFM_FMT_CSV, 1280, 720, &w, &err), &err);
  while (c && r && w && elfm_reader_read(r, c, &err) == ELFM_OK && (c->n || c->n_trig)) {
    size_t k = 0;
    for (size_t i = 0; i < c->n; i++)
      if (c->x[i] < x_max) {
        c->t_us[k] = c->t_us[i];
        c->x[k] = c->x[i];
        c->y[k] = c->y[i];
        c->p[k++] = c->p[i];
      }
    c->n = k;
    CHECK_OK(elfm_writer_write(w, c, &err), &err);
  }
  if (w) CHECK_OK(elfm_writer_close(w, &err), &err);
  elfm_reader_close(r);
  elfm_chunk_free(c);
}

/* The files in directory d (-1: cannot read it) */
static int dir_entries(const char *d)
{
  DIR *h = opendir(d);
  if (!h) return -1;
  int n = 0;
  for (struct dirent *e; (e = readdir(h));) n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
  closedir(h);
  return n;
}

/* The focus the last refine said (err.txt): where the images were
 * strongest, and as read forwards and backwards (NaN: not said) */
static void said_focus(double *z, double *fw, double *bw)
{
  char text[20000];
  if (!cli_read_file(dir, "err.txt", text, sizeof text)) return;
  const char *a = strstr(text, "strongest at z "), *b = strstr(text, "read forwards, "),
             *c = strstr(text, ", and backwards, ");
  if (a) *z = atof(a + strlen("strongest at z "));
  if (b) *fw = atof(b + strlen("read forwards, "));
  if (c) *bw = atof(c + strlen(", and backwards, "));
}

static double flow_alpha(const char *calib)
{
  char args[3000], text[4000];
  snprintf(args, sizeof args, "track --calib %s/%s --events %s/flow/events.raw --out %s/tr --threads 2 --quiet", dir,
           calib, dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(args, sizeof args, "score --truth %s/flow/truth.csv --tracks %s/tr/tracks.csv --json", dir, dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  if (!cli_read_file(dir, "out.txt", text, sizeof text)) return NAN;
  const char *a = strstr(text, "\"alpha\":");
  return a ? atof(a + 8) : NAN;
}

static void test_cli(void)
{
  char args[3000], p[800];
  elfm_error err;
  elfm_calib optics, truth, r;
  if (!cli_test_ready(dir)) return;
  snprintf(args, sizeof args, "calib from-optics --out %s/optics.json", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  snprintf(p, sizeof p, "%s/optics.json", dir);
  CHECK_OK(elfm_calib_load(p, &optics, &err), &err);
  sweep_sim("zr", "--param optics.relay=1.28");

  /* the focal plane moved, then the relay's scale from the grid; the
   * sweep read backwards from a copy in TMPDIR, removed after */
  char tmp[700];
  snprintf(tmp, sizeof tmp, "%s/tmp", dir);
  CHECK(mkdir(tmp, 0700) == 0 && setenv("TMPDIR", tmp, 1) == 0);
  const double moved = refine("zr", "moved.json", "", &r, &truth);
  CHECK_MSG(dir_entries(tmp) == 0, "%d files left in TMPDIR", dir_entries(tmp));
  CHECK(cli_file_has(dir, "err.txt", "the sweep's images were strongest at z +") &&
        cli_file_has(dir, "err.txt", "(one way: the mean of the sweep read forwards, +") &&
        cli_file_has(dir, "err.txt", ", and backwards, +") &&
        cli_file_has(dir, "err.txt", "the focal plane moved there") &&
        cli_file_has(dir, "err.txt", "the views' grid is 1.02") &&
        cli_file_has(dir, "err.txt", "x the start's: the relay's magnification, um_per_px 0.9257 -> 0.90"));
  printf("a relay 2.4 %% longer than the optics': the focal plane %+.2f um off, um_per_px %+.2f %%, disparities "
         "%+.2f %% (the optics' %+.2f / %+.2f %%)\n", moved, 100 * scale_off(&r, &truth), 100 * disparity_off(&r, &truth),
         100 * scale_off(&optics, &truth), 100 * disparity_off(&optics, &truth));
  /* the fit's own focus, +1.91; the two readings lean apart (+23.71 and
   * +20.18 um of the fitted depths) and their mean is taken */
  CHECK_MSG(fabs(moved) < 1.2, "the focal plane moved to %.2f um off", moved);
  double z_said = NAN, z_fw = NAN, z_bw = NAN;
  said_focus(&z_said, &z_fw, &z_bw);
  CHECK_MSG(z_fw - z_bw > 1 && fabs(z_said - 0.5 * (z_fw + z_bw)) < 0.006,
            "strongest at %+.2f, read forwards %+.2f, backwards %+.2f", z_said, z_fw, z_bw);
  CHECK_MSG(fabs(scale_off(&r, &truth)) < 0.0015 && fabs(disparity_off(&r, &truth)) < 0.0015,
            "um_per_px %.4f, disparities %.4f off", scale_off(&r, &truth), disparity_off(&r, &truth));
  /* no temporary file: the fit's own focus, and said */
  CHECK(setenv("TMPDIR", "/nonexistent-elfm-dir", 1) == 0);
  const double forwards = refine("zr", "forwards.json", "", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "no temporary file for the sweep read backwards (TMPDIR?): its focus read "
                     "forwards alone") && !cli_file_has(dir, "err.txt", "backwards, +"));
  printf("... read forwards alone (no TMPDIR): %+.2f um off\n", forwards);
  CHECK_MSG(forwards > 1.5 && forwards < 2.5, "forwards alone: %.2f um off", forwards);
  CHECK(setenv("TMPDIR", tmp, 1) == 0);
  /* --keep-scale: the optics' scale */
  const double still = refine("zr", "still.json", "--keep-scale", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "the scale kept (--keep-scale)"));
  CHECK_MSG(fabs(still - moved) < 1e-9, "--keep-scale moved the focal plane to %.3f, not %.3f", still, moved);
  CHECK_MSG(fabs(scale_off(&r, &optics)) < 1e-6 && fabs(disparity_off(&r, &optics)) < 1e-3,
            "--keep-scale: um_per_px %.3g, disparities %.3g off the optics'", scale_off(&r, &optics),
            disparity_off(&r, &optics));
  /* the piezo's speed given too: the disparities follow it, from the
   * grid's scale */
  const double piezo = refine("zr", "piezo.json", "--sweep-um-per-ms 0.2", &r, &truth);
  printf("... with the piezo's speed: the focal plane %+.2f um, um_per_px %+.2f %%, disparities %+.2f %%\n", piezo,
         100 * scale_off(&r, &truth), 100 * disparity_off(&r, &truth));
  CHECK(cli_file_has(dir, "err.txt", "the disparities scaled by 0.9"));
  CHECK_MSG(fabs(scale_off(&r, &truth)) < 0.005 && fabs(disparity_off(&r, &truth)) < 0.01,
            "um_per_px %.4f, disparities %.4f off", scale_off(&r, &truth), disparity_off(&r, &truth));
  /* --keep-focal-plane: neither seen */
  const double kept = refine("zr", "kept.json", "--keep-focal-plane", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "the focal plane kept (--keep-focal-plane)") &&
        !cli_file_has(dir, "err.txt", "the views' grid"));
  printf("... --keep-focal-plane: %+.2f um off\n", kept);
  CHECK_MSG(fabs(kept) > 15, "--keep-focal-plane: the focal plane %.2f um off", kept);
  CHECK(fabs(scale_off(&r, &optics)) < 1e-6);

  /* the bead swept up and then down again (the scene's triangle over 1.8
   * s): each way's focus, their mean within 0.7 um (+0.39 measured, where
   * one way up left +1.91 before it was read both ways); not read
   * backwards (which gave +0.34-0.56 on seeds 1-4, not better) */
  sweep_sim("zud", "--param optics.relay=1.28 --duration-ms 1800");
  const double both = refine("zud", "both.json", "", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "(the mean of the way up's +") && !cli_file_has(dir, "err.txt", "backwards") &&
        cli_file_has(dir, "err.txt", "the focal plane moved there"));
  printf("... swept up and down: the focal plane %+.2f um off, um_per_px %+.2f %%\n", both,
         100 * scale_off(&r, &truth));
  CHECK_MSG(fabs(both) < 0.7, "up and down: the focal plane %.2f um off", both);
  CHECK_MSG(fabs(scale_off(&r, &truth)) < 0.002, "up and down: um_per_px %.4f off", scale_off(&r, &truth));

  /* a one-way sweep twice as fast (0.4 mm/s): read backwards on the
   * integral with its start levels read back, it leant 7.2 um the other
   * way (a mean 3.85 um off); started empty, both readings lean less, and
   * their mean is within 1.2 um (+0.59 measured; the fit's own +0.62) */
  sweep_sim("zfast", "--param optics.relay=1.28 --param motion.speed_mm_per_s=0.4 --duration-ms 450");
  const double fast = refine("zfast", "fast.json", "", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "(one way: the mean of the sweep read forwards, +"));
  printf("... one way at 0.4 mm/s: the focal plane %+.2f um off\n", fast);
  CHECK_MSG(fabs(fast) < 1.2, "one way at 0.4 mm/s: the focal plane %.2f um off", fast);

  /* the same sweep as a CSV of the events left of x = 1200 (no geometry
   * of its own, narrower than the sensor): the reversed copy takes the
   * sensor's geometry, and both readings are made */
  write_roi_csv("zfast/events.raw", "roi.csv", 1200);
  refine_run("roi.csv", "roi.json", "", 0);
  CHECK(cli_file_has(dir, "err.txt", "(one way: the mean of the sweep read forwards, +") &&
        !cli_file_has(dir, "err.txt", "its focus read forwards alone"));

  /* the time surface given: refused, and the integral named */
  refine_run("zr/events.raw", "exp.json", "--repr exp", 1);
  CHECK(cli_file_has(dir, "err.txt", "too few views or frames") &&
        cli_file_has(dir, "err.txt", "On --repr exp, a slow object shows only where it moved: the integral"));

  /* sensor noise, 10 Hz a pixel (the simulator's 2), the sweep at 0.4
   * mm/s (half the events to read): taken for several objects, read again
   * through the 3 x 3 median and fitted (focal plane -0.71 um, within
   * 1.2); refused with --median 0 given. At 8 Hz the forward reading fits
   * as it is, the backward one (the noise's polarities swapped) only
   * through the median: both readings are made (+0.14) */
  sweep_sim("zn10", "--param optics.relay=1.28 --param sensor.shot_noise_hz=10 --param motion.speed_mm_per_s=0.4 "
            "--duration-ms 450");
  const double noisy = refine("zn10", "noisy.json", "", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "noise? read again through the 3 x 3 median filter (--median 3)") &&
        cli_file_has(dir, "err.txt", "(one way: the mean of the sweep read forwards, +"));
  printf("... under 10 Hz of noise a pixel: the focal plane %+.2f um off, um_per_px %+.2f %%\n", noisy,
         100 * scale_off(&r, &truth));
  CHECK_MSG(fabs(noisy) < 1.2 && fabs(scale_off(&r, &truth)) < 0.002, "noise: the focal plane %.2f um off, "
            "um_per_px %.4f", noisy, scale_off(&r, &truth));
  refine_run("zn10/events.raw", "noisy0.json", "--median 0", 1);
  CHECK(cli_file_has(dir, "err.txt", "several objects in the views") && !cli_file_has(dir, "err.txt", "noise?"));
  sweep_sim("zn8", "--param optics.relay=1.28 --param sensor.shot_noise_hz=8 --param motion.speed_mm_per_s=0.4 "
            "--duration-ms 450");
  const double noisy8 = refine("zn8", "noisy8.json", "", &r, &truth);
  CHECK(!cli_file_has(dir, "err.txt", "noise?") &&
        cli_file_has(dir, "err.txt", "(one way: the mean of the sweep read forwards, +"));
  printf("... under 8 Hz: the focal plane %+.2f um off\n", noisy8);
  CHECK_MSG(fabs(noisy8) < 1.2, "8 Hz: the focal plane %.2f um off", noisy8);

  /* the optics' own relay: the focus found within 2 um, nothing moved */
  sweep_sim("zs", "");
  const double right = refine("zs", "right.json", "", &r, &truth);
  CHECK(cli_file_has(dir, "err.txt", "as near as a sweep tells it, the focal plane kept") &&
        !cli_file_has(dir, "err.txt", "the views' grid"));
  printf("the optics' own relay: the focal plane %+.2f um off\n", right);
  CHECK_MSG(fabs(right) < 0.5, "the right relay: the focal plane %.2f um off", right);
  CHECK(fabs(scale_off(&r, &optics)) < 1e-6);

  snprintf(args, sizeof args, "simulate flow --seed 2 --duration-ms 100 --param optics.relay=1.28 --out %s/flow "
           "--quiet", dir);
  CHECK_EQ_INT(cli_run(dir, args), 0);
  const double a_moved = flow_alpha("moved.json"), a_still = flow_alpha("still.json"),
               a_kept = flow_alpha("kept.json");
  printf("flow 100 ms seed 2 under that relay: alpha %.4f with the focal plane and the scale moved, %.4f with the "
         "scale kept, %.4f with both kept\n", a_moved, a_still, a_kept);
  CHECK_MSG(a_moved >= 0.85, "alpha %.4f with the focal plane and the scale moved", a_moved);
  CHECK_MSG(a_still >= 0.70 && a_still < a_moved, "alpha %.4f with the scale kept", a_still);
  CHECK_MSG(a_kept < 0.1, "alpha %.4f with the focal plane kept", a_kept);

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

int main(void)
{
  elfm_calib c;
  if (!calib_test_default(&c)) return check_report();
  test_by_hand(&c);
  test_move(&c);
  test_cli();
  return check_report();
}
