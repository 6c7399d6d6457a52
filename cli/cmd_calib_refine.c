/* cmd_calib_refine.c — eventlfm calib refine: fit the views' centres of a
 * calibration to a recording of bright points (beads), so that a
 * calibration built from the optics (calib from-optics: nominal view
 * positions) or one that has drifted matches the microscope as it is.
 *
 * Each pass refocuses the first --ms of the recording with the current
 * centres, detects the bright peaks of every volume (on the worker threads,
 * like track), fits each from all views (elfm_refocus_localize_misses) and
 * collects where each view's image lay off the fit; then every view moves
 * by the median of its misses (elfm_calib_refine_apply, recon/calib_refine.c,
 * which also says what no recording can fix). Why it matters: on the
 * simulated flow scene, view centres off by 1 px (random per view) took
 * the tracks' alpha from 0.862 to 0.768 (docs/recon.md).
 *
 * Before the passes, the lens array's turn against the sensor's rows: a
 * turn of 1 degree moves the outer views' centres by 5-8 px (beyond the
 * view fit's window; the coarse step could bring in only some views) and a
 * turn of 3 degrees beyond the coarse step's reach, and turns the
 * disparities, which no centre can make up (flow 100 ms at 3 degrees, the
 * centres right: alpha 0.869 against 0.893). So the turns within
 * --turn-deg are tried, each on the first 20 ms, and the one whose volumes
 * are sharpest is kept (turn_search); after the passes the disparities turn
 * to the fitted grid of centres (elfm_calib_turns). */
#include <getopt.h>
#include <inttypes.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cmd_calib_refine.h"
#include "elfm_tracker.h"

static const char *const C = "calib refine";

/* --sweep reads this much of the recording unless --ms is given: a sweep
 * of 180 um at 0.2 mm/s takes 0.9 s; every pass reads it whole */
#define SWEEP_MS 5000.0

/* The coarse step's points per volume: the brightest, whose images stand
 * out in every view. */
#define VOTERS_PER_VOLUME 50

static elfm_status worker(const elfm_volume *v, const elfm_frame *frame, const elfm_refocus_plan *plan,
                          int slot, int thread, void *user, elfm_error *err)
{
  refine_ctx *c = user;
  refine_slot *s = &c->slot[slot];
  elfm_detection *det = c->det + (size_t)thread * (size_t)c->max_pts;
  int n = 0;
  s->n = 0;
  if (c->sweep) {
    /* each view's spots (the callback keeps them in frame order) */
    s->t_us = frame->t_us;
    return elfm_calib_sweep_spots(c->sweep, frame, s->img, err);
  }
  elfm_status st = elfm_peaks_detect(c->pk[thread], v, det, c->max_pts, &n, err);
  if (st != ELFM_OK) return st;
  if (c->scoring) {
    /* Squares, so that a point's light gathered in one peak counts more
     * than the same light spread over several lower ones, as the views of
     * a turned array leave it */
    s->score = 0;
    s->n_scored = n < VOTERS_PER_VOLUME ? n : VOTERS_PER_VOLUME;
    for (int k = 0; k < s->n_scored; k++) s->score += det[k].intensity * det[k].intensity;
    return ELFM_OK;
  }
  if (c->voting) {
    /* the brightest points vote (the callback, in frame order) */
    s->frame = frame;
    for (int k = 0; k < n && k < VOTERS_PER_VOLUME; k++) {
      s->pos[k][0] = det[k].x_um;
      s->pos[k][1] = det[k].y_um;
      s->pos[k][2] = det[k].z_um;
      s->n++;
    }
    return ELFM_OK;
  }
  for (int k = 0; k < n; k++) {
    elfm_localize_result r;
    double *miss = s->miss + (size_t)s->n * 2 * (size_t)c->nv, *wt = s->wt + (size_t)s->n * (size_t)c->nv;
    if (!elfm_refocus_localize_misses(plan, frame, elfm_volume_x_vox(v, det[k].x_um),
                                      elfm_volume_y_vox(v, det[k].y_um), elfm_volume_z_vox(v, det[k].z_um),
                                      &c->lo, &r, miss, wt))
      continue;
    double *at = s->at + (size_t)s->n * 2 * (size_t)c->nv;
    for (int u = 0; u < c->nv; u++)
      elfm_calib_project(c->cal, u, det[k].x_um, det[k].y_um, det[k].z_um, &at[2 * u], &at[2 * u + 1]);
    s->n++;
  }
  return ELFM_OK;
}

static elfm_status on_volume(const elfm_volume *v, int slot, void *user, elfm_error *err)
{
  (void)v;
  (void)err;
  refine_ctx *c = user;
  const refine_slot *s = &c->slot[slot];
  if (c->scoring) {
    c->score += s->score;
    c->n_scored += s->n_scored;
    c->volumes++;
    if (c->count_stop > 0 && c->n_scored >= c->count_stop) {
      c->count_stopped = 1;
      return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "enough peaks counted");
    }
    return ELFM_OK;
  }
  if (c->sweep) {
    elfm_calib_sweep_add(c->sweep, s->t_us, s->img);
    c->volumes++;
    return ELFM_OK;
  }
  if (c->voting) {
    for (int k = 0; k < s->n; k++)
      elfm_calib_refine_vote(c->acc, c->cal, s->frame, s->pos[k][0], s->pos[k][1], s->pos[k][2]);
    c->volumes++;
    return ELFM_OK;
  }
  for (int k = 0; k < s->n; k++)
    elfm_calib_refine_add(c->acc, s->at + (size_t)k * 2 * (size_t)c->nv, s->miss + (size_t)k * 2 * (size_t)c->nv,
                          s->wt + (size_t)k * (size_t)c->nv);
  c->volumes++;
  return ELFM_OK;
}

/* The first event's time: the passes read [t0, t0 + ms). */
static elfm_status first_event_us(const char *path, const elfm_reader_options *ro, int64_t *t0,
                                  elfm_error *err)
{
  elfm_reader *r = NULL;
  elfm_event_chunk *ch = NULL;
  elfm_status st = elfm_reader_open(path, ro, &r, err);
  if (st == ELFM_OK && !(ch = elfm_chunk_create(4096, err))) st = ELFM_ERR_NOMEM;
  *t0 = INT64_MIN;
  while (st == ELFM_OK) {
    st = elfm_reader_read(r, ch, err);
    if (st != ELFM_OK || ch->n > 0) break;
    if (ch->n == 0 && ch->n_trig == 0) break; /* end of file */
  }
  if (st == ELFM_OK && ch->n > 0) *t0 = ch->t_us[0];
  if (st == ELFM_OK && *t0 == INT64_MIN)
    st = elfm_error_set(err, ELFM_ERR_FORMAT, path, -1, "no events to fit the views to");
  elfm_chunk_free(ch);
  elfm_reader_close(r);
  return st;
}

static void ctx_free(refine_ctx *c, int threads, int slots)
{
  for (int t = 0; c->pk && t < threads; t++) elfm_peaks_free(c->pk[t]);
  free(c->pk);
  free(c->det);
  for (int s = 0; c->slot && s < slots; s++) {
    free(c->slot[s].miss);
    free(c->slot[s].wt);
    free(c->slot[s].at);
    free(c->slot[s].pos);
    free(c->slot[s].img);
  }
  free(c->slot);
  elfm_calib_refine_free(c->acc);
}

static int parse(int argc, char **argv, refine_opts *o)
{
  enum { O_CALIB = 256, O_EVENTS, O_OUT, O_MS, O_PASSES, O_THR, O_MINV, O_MINP, O_SEARCH, O_TURN, O_SWEEP,
         O_SPEED, O_KEEP_FOCUS, O_KEEP_SCALE, O_QUIET };
  static const struct option opts[] = {
      CLI_RECON_LONG_OPTIONS,
      {"calib", required_argument, 0, O_CALIB}, {"events", required_argument, 0, O_EVENTS},
      {"out", required_argument, 0, O_OUT}, {"ms", required_argument, 0, O_MS},
      {"passes", required_argument, 0, O_PASSES}, {"threshold", required_argument, 0, O_THR},
      {"min-views", required_argument, 0, O_MINV}, {"min-points", required_argument, 0, O_MINP},
      {"search-px", required_argument, 0, O_SEARCH}, {"turn-deg", required_argument, 0, O_TURN},
      {"sweep", no_argument, 0, O_SWEEP}, {"sweep-um-per-ms", required_argument, 0, O_SPEED},
      {"keep-focal-plane", no_argument, 0, O_KEEP_FOCUS}, {"keep-scale", no_argument, 0, O_KEEP_SCALE},
      {"quiet", no_argument, 0, O_QUIET},
      {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  memset(o, 0, sizeof *o);
  calib_refine_recon_defaults(&o->recon);
  o->ms = 200;
  o->passes = 4;
  o->threshold = 60;
  o->min_views = 0;
  o->min_points = 20;
  o->search_px = 12;
  o->turn_deg = 5;
  o->repr_auto = 1;
  cli_recon_parse rp = {.ro = &o->recon};
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    if (c == CLI_RO_REPR || c == CLI_RO_TAU || c == CLI_RO_POLARITY || c == CLI_RO_BLUR) o->repr_auto = 0;
    if (c == CLI_RO_MEDIAN) o->median_given = 1;
    const int k = cli_parse_recon_option(C, c, optarg, &rp);
    if (k == 0) return CLI_USAGE;
    if (k > 0) continue;
    int ok = 1;
    switch (c) {
    case 'h': calib_refine_usage(stdout); return -1;
    case O_CALIB: o->calib = optarg; break;
    case O_EVENTS: o->events = optarg; break;
    case O_OUT: o->out = optarg; break;
    case O_MS: o->ms_given = 1; ok = cli_parse_double_in(C, "--ms", optarg, 0, 1, 1e7, "> 0", &o->ms); break;
    case O_PASSES: ok = cli_parse_int_in(C, "--passes", optarg, 0, 20, "0..20", &o->passes); break;
    case O_THR:
      o->threshold_given = 1;
      ok = cli_parse_double_in(C, "--threshold", optarg, 0, 1, 1e9, "> 0", &o->threshold);
      break;
    case O_MINV: ok = cli_parse_int_in(C, "--min-views", optarg, 3, ELFM_MAX_VIEWS, "3..81", &o->min_views); break;
    case O_MINP: ok = cli_parse_int_in(C, "--min-points", optarg, 1, 1000000, "1..1000000", &o->min_points); break;
    case O_SEARCH: ok = cli_parse_int_in(C, "--search-px", optarg, 0, 64, "0..64", &o->search_px); break;
    case O_TURN: ok = cli_parse_double_in(C, "--turn-deg", optarg, 0, 0, 45, "0..45", &o->turn_deg); break;
    case O_SWEEP: o->sweep = 1; break;
    case O_SPEED:
      o->sweep = 1;
      ok = cli_parse_double_in(C, "--sweep-um-per-ms", optarg, 0, 1, 1e6, "> 0", &o->sweep_speed);
      break;
    case O_KEEP_FOCUS: o->keep_focus = 1; break;
    case O_KEEP_SCALE: o->keep_scale = 1; break;
    case O_QUIET: o->quiet = 1; break;
    default: return cli_bad_option(C, c, argv);
    }
    if (!ok) return CLI_USAGE;
  }
  if (optind < argc) return cli_message(C, CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!o->calib || !o->events || !o->out)
    return cli_message(C, CLI_USAGE, "--calib, --events and --out are required (see --help)");
  if (o->recon.from_us != INT64_MIN && o->recon.to_us != INT64_MAX && o->recon.to_us <= o->recon.from_us)
    return cli_message(C, CLI_USAGE, "--to-us must be after --from-us");
  if (!cli_check_recon_options(C, &rp)) return CLI_USAGE;
  o->istart_given = rp.istart_given;
  cli_recon_planes(&rp, o->planes_um);
  if (o->sweep && !o->ms_given) o->ms = SWEEP_MS;
  if (o->repr_auto) {
    /* the same options on the integral, with its own defaults (both
     * polarities, its leak, its start: cli_check_recon_options) */
    o->recon_integral = o->recon;
    o->recon_integral.framer.repr = ELFM_REPR_INTEGRAL;
    cli_recon_parse ri = rp;
    ri.ro = &o->recon_integral;
    if (!cli_check_recon_options(C, &ri)) return CLI_USAGE;
  }
  return CLI_OK;
}

/* A pass's moves (2 per view) into the running totals; their RMS and
 * largest, px, for the progress line. */
void refine_add_moves(int nv, const double *shift, double *total, double *rms, double *worst)
{
  double ss = 0;
  *worst = 0;
  for (int v = 0; v < nv; v++) {
    const double m = hypot(shift[2 * v], shift[2 * v + 1]);
    *worst = fmax(*worst, m);
    ss += m * m;
    total[2 * v] += shift[2 * v];
    total[2 * v + 1] += shift[2 * v + 1];
  }
  *rms = sqrt(ss / nv);
}

/* The turn's search reads this much of the stretch per turn tried (27
 * turns within 5 degrees): on flow, 20 volumes of ~20 beads each. Where
 * the sharpest turn has fewer peaks than TURN_MIN_PEAKS (blinking beads,
 * seen in a few pulses), the search runs again on 4 times as much, up to
 * the passes' stretch. */
#define TURN_SEARCH_MS 20.0
#define TURN_MIN_PEAKS 100
/* Fewer peaks than this over the whole stretch tell no turn: one bead
 * swept through z (zsweep seed 1, its first 200 ms on the time surface)
 * gave 1 peak, whose sharpest turn was -3 degrees (the array is not
 * turned); the passes then failed, but a recording with a few more points
 * would have gone on with that turn. So the array stays as it is. */
#define TURN_JUDGE_MIN_PEAKS 20
/* The integral's peaks, chosen for slow objects (choose_repr), above this
 * when --threshold is not given: its images are dimmer than the time
 * surface's (track's thresholds: 25 on the integral, 45 on the surface) */
#define REFINE_INTEGRAL_THRESHOLD 30
double refine_integral_threshold(const refine_opts *o)
{
  return o->threshold_given ? o->threshold : REFINE_INTEGRAL_THRESHOLD;
}

/* One pass: refocus, fit, collect (into c->acc). */
elfm_status refine_run_pass(refine_ctx *c, const elfm_calib *cal, elfm_recon_options ro,
                            elfm_error *err)
{
  ro.worker = worker;
  ro.worker_user = c;
  ro.on_volume_slot = on_volume;
  ro.progress = NULL;
  c->volumes = 0;
  return elfm_recon_run(c->events, cal, &ro, NULL, c, NULL, err);
}

/* How sharp the volumes of cal turned by a degrees are: the squared heights
 * of each volume's brightest peaks, summed (the worker). */
static elfm_status turn_score(refine_ctx *c, const elfm_calib *cal, double a, elfm_recon_options ro,
                              double *score, int64_t *n_scored, elfm_error *err)
{
  elfm_calib t = *cal;
  elfm_calib_turn(&t, a);
  c->scoring = 1;
  c->score = 0;
  c->n_scored = 0;
  const elfm_status st = refine_run_pass(c, &t, ro, err);
  c->scoring = 0;
  *score = c->score;
  if (n_scored) *n_scored = c->n_scored;
  return st;
}

/* The lens array's turn within +-max_deg that gives the sharpest volumes
 * (*top_score: their score, 0 when no turn gave a peak): every 0.5
 * degrees, then every 0.1 around the best, then the vertex of the parabola
 * through the best and its two neighbours. On flow a turn 0.5 degrees off
 * still gives a fifth of the right one's score, 1 degree off almost none
 * (its outer views' images miss by 5-8 px), so 0.5 is the coarsest step
 * that cannot step over the right turn. Within 0.1 degrees, a view 300 px
 * from the grid's middle is within 0.5 px, which the coarse step and the
 * passes then fit. *too_few: peaks were seen, but fewer than
 * TURN_JUDGE_MIN_PEAKS, and no turn was judged (*best_deg 0). */
static elfm_status turn_search(refine_ctx *c, const elfm_calib *cal, double max_deg,
                               elfm_recon_options ro, double *best_deg, int *tried, double *top_score,
                               double *search_ms, int64_t *peaks, int *too_few, elfm_error *err)
{
  const int64_t to_us = ro.to_us;
  double best = 0, best_score = -1;
  *tried = 0;
  for (double ms = TURN_SEARCH_MS;; ms *= 4) {
    const int64_t t_end = ro.from_us + (int64_t)llround(ms * 1000);
    ro.to_us = to_us < t_end ? to_us : t_end;
    *search_ms = (double)(ro.to_us - ro.from_us) / 1000.0;
    best = 0;
    best_score = -1;
    const int n0 = (int)floor(max_deg / 0.5 + 1e-9);
    if (!c->o->quiet)
      fprintf(stderr, "calib refine: the lens array's turn: trying %d turns within +-%g deg on %g ms\n",
              2 * n0 + 1, max_deg, *search_ms);
    for (int k = -n0; k <= n0; k++) {
      double sc;
      int64_t np;
      elfm_status st = turn_score(c, cal, 0.5 * k, ro, &sc, &np, err);
      if (st != ELFM_OK) return st;
      ++*tried;
      /* on a tie the smaller turn, so that no peaks at all leave none */
      if (sc > best_score || (sc == best_score && abs(k) < fabs(best) / 0.5)) {
        best_score = sc;
        best = 0.5 * k;
        *peaks = np;
      }
    }
    if (*peaks >= TURN_MIN_PEAKS || ro.to_us >= to_us) break;
  }
  *top_score = best_score;
  *best_deg = 0;
  *too_few = best_score > 0 && *peaks < TURN_JUDGE_MIN_PEAKS;
  if (!(best_score > 0) || *too_few) return ELFM_OK;
  /* the best of every 0.5 degrees lies within 0.25 of the sharpest */
  double sc_at[7];
  for (int k = -3; k <= 3; k++) {
    const double a = best + 0.1 * k;
    sc_at[k + 3] = k == 0 ? best_score : -1;
    if (k == 0 || fabs(a) > max_deg + 1e-9) continue;
    elfm_status st = turn_score(c, cal, a, ro, &sc_at[k + 3], NULL, err);
    if (st != ELFM_OK) return st;
    ++*tried;
  }
  int kb = 3;
  for (int k = 0; k < 7; k++)
    if (sc_at[k] > sc_at[kb]) kb = k;
  double a = best + 0.1 * (kb - 3);
  if (kb > 0 && kb < 6 && sc_at[kb - 1] >= 0 && sc_at[kb + 1] >= 0) {
    const double den = sc_at[kb - 1] - 2 * sc_at[kb] + sc_at[kb + 1];
    if (den < 0) a += 0.1 * 0.5 * (sc_at[kb - 1] - sc_at[kb + 1]) / den;
  }
  *top_score = sc_at[kb];
  *best_deg = fmin(fmax(a, -max_deg), max_deg);
  return ELFM_OK;
}

/* The peak detectors (one per thread) for peaks above thr */
elfm_status refine_set_threshold(refine_ctx *c, const elfm_calib *cal, double thr, elfm_error *err)
{
  elfm_peaks_options po;
  elfm_peaks_options_default(&po);
  po.absolute = thr;
  for (int t = 0; t < c->threads; t++) {
    elfm_peaks_free(c->pk[t]);
    if (!(c->pk[t] = elfm_peaks_create(&po, cal->view_w_px, cal->view_h_px, elfm_calib_n_planes(cal), err)))
      return ELFM_ERR_NOMEM;
  }
  return ELFM_OK;
}

/* Peaks (up to VOTERS_PER_VOLUME per volume) on ro's frames over the
 * stretch, at the calibration as it is; stops counting at `enough`. */
static elfm_status count_peaks(refine_ctx *c, const elfm_calib *cal, elfm_recon_options ro, int64_t enough,
                               int64_t *n, elfm_error *err)
{
  double score;
  c->count_stop = enough;
  c->count_stopped = 0;
  elfm_status st = turn_score(c, cal, 0.0, ro, &score, n, err);
  c->count_stop = 0;
  if (c->count_stopped) {
    elfm_error_clear(err);
    st = ELFM_OK;
  }
  return st;
}

/* Objects that move slowly (one bead swept through z at 0.2 mm/s) fire few
 * of their pixels in a window: the time surface shows them in no peak,
 * the integral (each pixel's leaky sum of events) does. zsweep seed 1 over
 * 900 ms: 2 peaks on the time surface, 189 on the integral, on which the
 * refinement works (docs/recon.md "Refining on one bead swept through z").
 * So with the representation not given and fewer than
 * TURN_JUDGE_MIN_PEAKS peaks on the time surface over the whole stretch,
 * the integral is counted too, and taken if it shows that many; as track
 * does with too few peaks to judge (cmd_track_auto.h). (Taken when it
 * showed merely more, 2 against 1 on the sweep's first 200 ms, its turn's
 * search then found 37 peaks of noise at -2.7 degrees.) Flow reaches the
 * count within its first volume or two. */
static elfm_status choose_repr(refine_ctx *c, const elfm_calib *cal, refine_opts *o, elfm_error *err)
{
  int64_t n_surface = 0, n_integral = 0;
  elfm_status st = count_peaks(c, cal, o->recon, TURN_JUDGE_MIN_PEAKS, &n_surface, err);
  if (st != ELFM_OK || n_surface >= TURN_JUDGE_MIN_PEAKS) return st;
  const double thr = refine_integral_threshold(o);
  if ((st = refine_set_threshold(c, cal, thr, err)) != ELFM_OK) return st;
  st = count_peaks(c, cal, o->recon_integral, TURN_JUDGE_MIN_PEAKS, &n_integral, err);
  if (st != ELFM_OK) return st;
  if (n_integral < TURN_JUDGE_MIN_PEAKS) return refine_set_threshold(c, cal, o->threshold, err);
  if (!o->quiet)
    fprintf(stderr, "calib refine: %" PRId64 " peaks above --threshold on the time surface over the %g ms, "
            "at least %" PRId64 " above %g on the integral: refining on --repr integral (objects that move "
            "slowly; --repr exp keeps the time surface; for one object swept through z, --sweep finds "
            "the views from centres further off, and sooner)\n", n_surface, o->ms, n_integral, thr);
  o->recon = o->recon_integral;
  o->threshold = thr;
  return ELFM_OK;
}

int cmd_calib_refine(int argc, char **argv)
{
  refine_opts o;
  const int pr = parse(argc, argv, &o);
  if (pr != CLI_OK) return pr < 0 ? CLI_OK : pr;
#if defined(__GLIBC__)
  /* The command runs the pipeline ~30 times over (the turn's search, the
   * coarse step, the passes). Its volumes and frames (4-8 MB each) came
   * each time as fresh pages from the system, zeroed by the kernel; kept
   * in the heap from run to run instead. Flow 100 ms, --ms 100: with the
   * search 6.5 s -> 3.5-3.9 s wall (two runs each); without it 1.93 ->
   * 1.68 s (7 pairs), system time 0.78 -> 0.38 s. */
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
  elfm_error err;
  elfm_error_clear(&err);
  elfm_calib cal;
  if (elfm_calib_load(o.calib, &cal, &err)) return cli_fail(C, &err);
  /* 12 of the paper's 25 views, scaled as track scales its counts: a
   * 3 x 3 array's 9 views need 5, where 12 could never agree */
  if (o.min_views == 0) o.min_views = cli_views_scale(12, cal.n_views) > 3 ? cli_views_scale(12, cal.n_views) : 3;
  if (o.min_views > cal.n_views)
    return cli_message(C, CLI_USAGE, "--min-views %d: %s has %d views", o.min_views, o.calib, cal.n_views);
  /* the passes may refocus on other planes (--z-*-um); the file written
   * keeps the calibration's own */
  const double z_file[3] = {cal.z_min_um, cal.z_max_um, cal.z_step_um};
  if (!cli_apply_planes(C, o.planes_um, o.calib, &cal)) return CLI_USAGE;
  /* Every pass reads the same stretch: --ms from the first event, or from
   * --from-us (beads may enter the field late), cut at --to-us. */
  int64_t t0 = o.recon.from_us;
  if (t0 == INT64_MIN && first_event_us(o.events, &o.recon.reader, &t0, &err) != ELFM_OK)
    return cli_fail(C, &err);
  const int64_t t1 = t0 + (int64_t)llround(o.ms * 1000);
  o.recon.from_us = t0;
  if (o.recon.to_us > t1) o.recon.to_us = t1;
  o.recon_integral.from_us = o.recon.from_us;
  o.recon_integral.to_us = o.recon.to_us;

  int threads = 0, slots = 0;
  if (elfm_recon_layout(&o.recon, &threads, &slots, &err) != ELFM_OK) return cli_fail(C, &err);
  refine_ctx c;
  memset(&c, 0, sizeof c);
  c.o = &o;
  c.events = o.events;
  c.nv = cal.n_views;
  c.max_pts = 1000;
  c.threads = threads;
  c.pk = calloc((size_t)threads, sizeof *c.pk);
  c.det = malloc((size_t)threads * (size_t)c.max_pts * sizeof *c.det);
  c.slot = calloc((size_t)slots, sizeof *c.slot);
  int ok = c.pk && c.det && c.slot;
  for (int s = 0; ok && s < slots; s++) {
    c.slot[s].miss = malloc((size_t)c.max_pts * 2 * (size_t)c.nv * sizeof(double));
    c.slot[s].wt = malloc((size_t)c.max_pts * (size_t)c.nv * sizeof(double));
    c.slot[s].at = malloc((size_t)c.max_pts * 2 * (size_t)c.nv * sizeof(double));
    c.slot[s].pos = malloc(VOTERS_PER_VOLUME * sizeof *c.slot[s].pos);
    c.slot[s].img = malloc(sizeof *c.slot[s].img);
    ok = c.slot[s].miss && c.slot[s].wt && c.slot[s].at && c.slot[s].pos && c.slot[s].img;
  }
  if (!ok) {
    ctx_free(&c, threads, slots);
    return cli_message(C, CLI_FAIL, "out of memory");
  }
  if (refine_set_threshold(&c, &cal, o.threshold, &err) != ELFM_OK) {
    ctx_free(&c, threads, slots);
    return cli_fail(C, &err);
  }
  if (elfm_calib_refine_create(c.nv, 200000, &c.acc, &err) != ELFM_OK) {
    ctx_free(&c, threads, slots);
    return cli_fail(C, &err);
  }
  double total[2 * ELFM_MAX_VIEWS] = {0};
  int rc = CLI_OK;
  c.cal = &cal;
  if (o.sweep) {
    rc = refine_sweep_step(&c, &cal, &o, total, &err);
    if (rc != CLI_OK) {
      ctx_free(&c, threads, slots);
      return rc;
    }
  } else if (o.repr_auto && choose_repr(&c, &cal, &o, &err) != ELFM_OK) {
    ctx_free(&c, threads, slots);
    return cli_fail(C, &err);
  }
  if (o.turn_deg > 0 && !o.sweep) {
    double a = 0, top = 0, search_ms = 0;
    int64_t peaks = 0;
    int tried = 0, too_few = 0;
    if (turn_search(&c, &cal, o.turn_deg, o.recon, &a, &tried, &top, &search_ms, &peaks, &too_few, &err) !=
        ELFM_OK) {
      ctx_free(&c, threads, slots);
      return cli_fail(C, &err);
    }
    elfm_calib_turn(&cal, a);
    if (!o.quiet && too_few)
      fprintf(stderr, "calib refine: %" PRId64 " peaks above --threshold in the first %g ms, too few to judge "
              "the lens array's turn by (%d or more): not turned\n", peaks, search_ms, TURN_JUDGE_MIN_PEAKS);
    else if (!o.quiet && top > 0)
      fprintf(stderr, "calib refine: the lens array's turn: %+.2f deg (the sharpest volumes of %d turns "
              "within +-%g deg on %g ms, %" PRId64 " peaks)\n", a, tried, o.turn_deg, search_ms, peaks);
    else if (!o.quiet)
      fprintf(stderr, "calib refine: no peak above --threshold in the first %g ms to judge the lens "
              "array's turn by: not turned\n", search_ms);
  }
  if (o.search_px > 0 && !o.sweep) {
    /* the coarse step (elfm_calib_refine_apply_votes) */
    double shift[2 * ELFM_MAX_VIEWS];
    int moved = 0;
    c.voting = 1;
    if (elfm_calib_refine_set_search(c.acc, o.search_px, &err) != ELFM_OK ||
        refine_run_pass(&c, &cal, o.recon, &err) != ELFM_OK) {
      ctx_free(&c, threads, slots);
      return cli_fail(C, &err);
    }
    const size_t nv = elfm_calib_refine_votes(c.acc);
    if (elfm_calib_refine_apply_votes(c.acc, &cal, shift, &moved, &err) != ELFM_OK) {
      ctx_free(&c, threads, slots);
      return cli_fail(C, &err);
    }
    c.voting = 0;
    double rms, worst;
    refine_add_moves(c.nv, shift, total, &rms, &worst);
    if (!o.quiet && nv < ELFM_CALIB_VOTES_MIN)
      fprintf(stderr, "calib refine: coarse step (+-%d px): %zu points, too few to move the views by (%d or "
              "more): skipped\n", o.search_px, nv, ELFM_CALIB_VOTES_MIN);
    else if (!o.quiet)
      fprintf(stderr, "calib refine: coarse step (+-%d px): %zu points, %d of %d views moved, RMS %.3f px, "
              "largest %.3f px\n", o.search_px, nv, moved, c.nv, rms, worst);
  }
  for (int pass = 0; pass < o.passes; pass++) {
    /* The first pass starts from centres that may be off by a few pixels:
     * a wider window (7 x 7) and a looser outlier test let the views find
     * their images; later passes use the view fit's own settings. */
    elfm_localize_options_default(&c.lo);
    c.lo.min_views = o.min_views;
    if (pass == 0) {
      c.lo.half_window_px = 3;
      c.lo.outlier_px = 3;
    }
    if (refine_run_pass(&c, &cal, o.recon, &err) != ELFM_OK) {
      rc = cli_fail(C, &err);
      break;
    }
    const size_t npts = elfm_calib_refine_points(c.acc);
    double shift[2 * ELFM_MAX_VIEWS];
    int moved = 0;
    if (elfm_calib_refine_apply(c.acc, o.min_points, &cal, shift, &moved, &err) != ELFM_OK) {
      rc = cli_fail(C, &err);
      break;
    }
    double rms, worst;
    refine_add_moves(c.nv, shift, total, &rms, &worst);
    if (!o.quiet)
      fprintf(stderr, "calib refine: pass %d: %" PRId64 " volumes, %zu points, %d of %d views moved, "
              "RMS %.3f px, largest %.3f px\n", pass + 1, c.volumes, npts, moved, c.nv,
              rms, worst);
    if (npts == 0) {
      rc = cli_message(C, CLI_FAIL, "%s: no point in %" PRId64 "..%" PRId64 " us could be fitted from "
                       "%d views (try a lower --threshold or --min-views, or a longer --ms%s)", o.events,
                       o.recon.from_us, o.recon.to_us, o.min_views,
                       o.recon.framer.repr == ELFM_REPR_INTEGRAL ? ""
                       : "; objects that move slowly, such as one bead swept through z, show on "
                         "--repr integral, with a --ms that covers the sweep; for one bead swept "
                         "through z, --sweep");
      break;
    }
  }
  /* the views the last pass placed on the others' grid */
  int still[ELFM_MAX_VIEWS];
  double spread[ELFM_MAX_VIEWS];
  for (int v = 0; v < cal.n_views; v++) still[v] = elfm_calib_refine_still(c.acc, v, &spread[v]);
  ctx_free(&c, threads, slots);
  if (rc != CLI_OK) return rc;
  /* the disparities to the fitted centres' turn */
  double turn_c, turn_d;
  elfm_calib_turns(&cal, &turn_c, &turn_d);
  elfm_calib_turn_disparities(&cal, turn_c - turn_d);
  if (!o.quiet) {
    fprintf(stderr, "calib refine: the fitted centres lie turned %+.3f deg against the lenslets' rows, "
            "the disparities %+.3f: these turned to match\n", turn_c, turn_d);
    for (int v = 0; v < cal.n_views; v++) {
      fprintf(stderr, "  view (%+d, %+d): moved (%+.3f, %+.3f) px%s", cal.views[v].i, cal.views[v].j,
              total[2 * v], total[2 * v + 1], still[v] ? "" : "\n");
      if (still[v])
        fprintf(stderr, ", placed on the other views' grid: its images stayed within %.2f px RMS of "
                "one place\n", spread[v]);
    }
  }
  cal.z_min_um = z_file[0];
  cal.z_max_um = z_file[1];
  cal.z_step_um = z_file[2];
  return cli_calib_write(C, &cal, o.out);
}
