/* cmd_bench.c — eventlfm bench: sweep the pipeline's settings on simulated
 * scenes and put speed against error (issue 7; docs/bench.md). This file:
 * the options, the sweep table and the run; cmd_bench.h says where the rest
 * lives.
 *
 * Every sweep point runs `eventlfm track` as a child process of this very
 * binary (/proc/self/exe), so that each point has its own wall time and its
 * own peak resident memory (wait4's ru_maxrss), and a crash or a rejected
 * option at one point cannot take the sweep down. Each run is then scored in
 * process with elfm_score_files (SPEC §7). The sweep is one-at-a-time around
 * the tracker's defaults (a full factorial of 11 axes would be thousands of
 * runs).
 *
 * Outputs in --out DIR: bench.csv (one row per point), bench.md (the same as
 * a Markdown table, plus the component benchmarks' output), plot/SCENE.dat and
 * plot.gnuplot -> bench_error_vs_speed.png (error against real-time factor,
 * Pareto front per scene), fig_s4.png (time surface vs accumulation MIPs at
 * 1, 5 and 10 ms), components/NAME.txt.
 */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cmd_bench.h"

/* Option names follow `eventlfm track --help` (tracker and recon helpers).
 * A point whose option the tracker rejects (exit 2) is reported as
 * "unsupported", not silently dropped. */
static const struct sweep_point SWEEP[] = {
    {"baseline", "defaults", {NULL}, 0, 1},
    {"accumulation", "dt 500 us", {"--dt-us", "500", NULL}, 0, 1},
    {"accumulation", "dt 1 ms", {"--dt-us", "1000", NULL}, 0, 0},
    {"accumulation", "dt 2 ms", {"--dt-us", "2000", NULL}, 0, 1},
    {"accumulation", "dt 5 ms", {"--dt-us", "5000", NULL}, 0, 1},
    {"representation", "exp time surface", {"--repr", "exp", NULL}, 0, 0},
    {"representation", "lin time surface", {"--repr", "lin", NULL}, 0, 1},
    {"representation", "counts", {"--repr", "count", NULL}, 0, 1},
    {"representation", "integral", {"--repr", "integral", NULL}, 0, 0},
    {"tau", "tau 250 us", {"--tau-us", "250", NULL}, 0, 1},
    {"tau", "tau 500 us", {"--tau-us", "500", NULL}, 0, 0},
    {"tau", "tau 1 ms", {"--tau-us", "1000", NULL}, 0, 0},
    {"tau", "tau 2 ms", {"--tau-us", "2000", NULL}, 0, 1},
    {"median", "median off", {"--median", "0", NULL}, 0, 1},
    {"median", "median 3x3", {"--median", "3", NULL}, 0, 0},
    {"median", "median 5x5", {"--median", "5", NULL}, 0, 0},
    {"planes", "dz 1 um", {NULL}, 1.0, 1},
    {"planes", "dz 2 um", {NULL}, 2.0, 0},
    {"planes", "dz 4 um", {NULL}, 4.0, 1},
    {"ghost", "ghost none", {"--ghost", "none", NULL}, 0, 1},
    {"ghost", "MAD k 3", {"--ghost", "mad", "--ghost-value", "3", NULL}, 0, 1},
    {"ghost", "frac 0.2 of max", {"--ghost", "frac", "--ghost-value", "0.2", NULL}, 0, 0},
    {"ghost", "agreement 0.8", {"--agree", "0.8", NULL}, 0, 1},
    {"refocus", "dense", {"--path", "dense", NULL}, 0, 1},
    {"refocus", "sparse", {"--path", "sparse", NULL}, 0, 1},
    {"refocus", "peaks binned 2x2", {"--bin-px", "2", NULL}, 0, 1},
    {"threads", "1 thread", {"--threads", "1", NULL}, 0, 1},
    {"threads", "2 threads", {"--threads", "2", NULL}, 0, 1},
    {"localize", "peak fit only", {"--localize", "peak", "--guided-views", "0", NULL}, 0, 1},
    {"localize", "view fit, no guided fit", {"--guided-views", "0", NULL}, 0, 1},
    {"localize", "view fit, power 1", {"--localize-power", "1", NULL}, 0, 0},
    {"deep window", "deep window off", {"--deep-window-us", "0", NULL}, 0, 1},
    {"link radius", "gate 2 um", {"--gate-um", "2", NULL}, 0, 1},
    {"link radius", "gate 4 um", {"--gate-um", "4", NULL}, 0, 0},
    {"link radius", "gate 8 um", {"--gate-um", "8", NULL}, 0, 1},
    {"gap", "gap 0", {"--max-gap", "0", NULL}, 0, 1},
    {"gap", "gap 5", {"--max-gap", "5", NULL}, 0, 0},
    {"gap", "gap 50", {"--max-gap", "50", NULL}, 0, 0},
    {"smoothing", "model auto (BIC)", {"--model", "auto", NULL}, 0, 0},
    {"smoothing", "const. velocity", {"--model", "cv", NULL}, 0, 1},
    {"smoothing", "const. accel.", {"--model", "ca", NULL}, 0, 0},
    {"smoothing", "spline", {"--model", "spline", NULL}, 0, 1},
};
#define N_SWEEP ((int)(sizeof SWEEP / sizeof SWEEP[0]))

/* This program's path: every child runs this very binary, never another
 * eventlfm found on PATH. */
static int self_exe(char *buf, size_t size)
{
  ssize_t n = readlink("/proc/self/exe", buf, size - 1);
  if (n <= 0) return -1;
  buf[n] = '\0';
  return 0;
}

static void bench_usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm bench [--quick] [--out DIR] [--scenes flow,stage,...]\n"
          "                      [--duration-ms D] [--seed N] [--timeout-s S]\n"
          "                      [--no-components] [--no-figures]\n"
          "\n"
          "Sweeps, one setting at a time around the tracker's defaults, on simulated scenes:\n"
          "accumulation time, representation, tau, median, plane spacing, ghost suppression,\n"
          "dense/sparse refocusing, threads, link radius, gap length, smoothing model. Each point\n"
          "runs `eventlfm track` as a child process and is scored (SPEC 7).\n"
          "Writes DIR/bench.csv, bench.md, bench_error_vs_speed.png (gnuplot), fig_s4.png and\n"
          "the output of the component benchmarks (build/bench/bench_*) in DIR/components/.\n"
          "  --quick         flow only, 50 ms, 27 points (a few minutes on 2 cores)\n"
          "  --out DIR       output directory (default bench_out)\n"
          "  --scenes LIST   built-in scenes (default: flow with --quick, else flow,stage)\n"
          "  --duration-ms D simulated duration per scene (default 50 quick, 300 full)\n"
          "  --timeout-s S   limit per child process (default 300 quick, 1800 full)\n"
          "  --max-points N  only the first N sweep points per scene (smoke tests)\n"
          "  --no-components skip the component benchmarks; --no-figures: no PNGs\n");
}

int cmd_bench(int argc, char **argv)
{
  enum { OPT_QUICK = 256, OPT_OUT, OPT_SCENES, OPT_DUR, OPT_SEED, OPT_TIMEOUT, OPT_NOCOMP,
         OPT_NOFIG, OPT_MAXPTS };
  static const struct option longopts[] = {
      {"quick", no_argument, NULL, OPT_QUICK},
      {"out", required_argument, NULL, OPT_OUT},
      {"scenes", required_argument, NULL, OPT_SCENES},
      {"duration-ms", required_argument, NULL, OPT_DUR},
      {"seed", required_argument, NULL, OPT_SEED},
      {"timeout-s", required_argument, NULL, OPT_TIMEOUT},
      {"no-components", no_argument, NULL, OPT_NOCOMP},
      {"no-figures", no_argument, NULL, OPT_NOFIG},
      {"max-points", required_argument, NULL, OPT_MAXPTS},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0}};
  struct bench_opts op;
  memset(&op, 0, sizeof op);
  op.out = "bench_out";
  op.seed = 1;
  op.components = 1;
  op.figures = 1;
  op.duration_ms = -1;
  op.timeout_s = -1;
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
    switch (c) {
    case 'h': bench_usage(stdout); return CLI_OK;
    case OPT_QUICK: op.quick = 1; break;
    case OPT_OUT: op.out = optarg; break;
    case OPT_SCENES:
      if (strlen(optarg) >= sizeof op.scenes || !optarg[0])
        return cli_message("bench", CLI_USAGE, "--scenes: bad list '%s'", optarg);
      cli_path_fmt(op.scenes, sizeof op.scenes, "%s", optarg);
      break;
    case OPT_DUR:
      if (!cli_parse_int("bench", "--duration-ms", optarg, &op.duration_ms)) return CLI_USAGE;
      if (op.duration_ms < 10 || op.duration_ms > 600000)
        return cli_message("bench", CLI_USAGE, "--duration-ms must be 10..600000");
      break;
    case OPT_SEED:
      if (!cli_parse_int64("bench", "--seed", optarg, &op.seed)) return CLI_USAGE;
      /* simulate's own rule, here before anything runs (it failed as the
       * simulation's error, exit 1) */
      if (op.seed < 0) return cli_message("bench", CLI_USAGE, "--seed must be >= 0");
      break;
    case OPT_TIMEOUT:
      if (!cli_parse_double("bench", "--timeout-s", optarg, &op.timeout_s)) return CLI_USAGE;
      if (!(op.timeout_s > 0)) return cli_message("bench", CLI_USAGE, "--timeout-s must be > 0");
      break;
    case OPT_NOCOMP: op.components = 0; break;
    case OPT_NOFIG: op.figures = 0; break;
    case OPT_MAXPTS:
      if (!cli_parse_int("bench", "--max-points", optarg, &op.max_points)) return CLI_USAGE;
      if (op.max_points < 1) return cli_message("bench", CLI_USAGE, "--max-points must be >= 1");
      break;
    default:
      cli_message("bench", CLI_USAGE, "unknown option or missing value: '%s'", argv[optind - 1]);
      bench_usage(stderr);
      return CLI_USAGE;
    }
  }
  if (optind < argc)
    return cli_message("bench", CLI_USAGE, "unexpected argument '%s'", argv[optind]);
  if (!op.scenes[0]) cli_path_fmt(op.scenes, sizeof op.scenes, "%s", op.quick ? "flow" : "flow,stage");
  if (op.duration_ms < 0) op.duration_ms = op.quick ? 50 : 300;
  if (op.timeout_s < 0) op.timeout_s = op.quick ? 300 : 1800;

  char self[PATH_MAX];
  if (self_exe(self, sizeof self) != 0)
    return cli_message("bench", CLI_FAIL, "cannot find this program's path (/proc/self/exe)");
  char dir[PATH_MAX];
  if (cli_mkdir_p(op.out) != 0 || !realpath(op.out, dir))
    return cli_message("bench", CLI_FAIL, "cannot create %s: %s", op.out, strerror(errno));

  /* Scenes: simulate each once. */
  struct scene_info sc[8];
  int n_sc = 0;
  {
    char list[256];
    cli_path_fmt(list, sizeof list, "%s", op.scenes);
    for (char *save = NULL, *tok = strtok_r(list, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
      if (n_sc == 8) return cli_message("bench", CLI_USAGE, "--scenes: at most 8 scenes");
      struct scene_info *si = &sc[n_sc];
      memset(si, 0, sizeof *si);
      cli_path_fmt(si->name, sizeof si->name, "%s", tok);
      cli_path_fmt(si->dir, sizeof si->dir, "%s/sim_%s", dir, tok);
      char dur[32], seed[32], logp[PATH_MAX];
      cli_path_fmt(dur, sizeof dur, "%d", op.duration_ms);
      cli_path_fmt(seed, sizeof seed, "%lld", (long long)op.seed);
      if (cli_mkdir_p(si->dir) != 0)
        return cli_message("bench", CLI_FAIL, "cannot create %s", si->dir);
      cli_path_fmt(logp, sizeof logp, "%s/simulate.log", si->dir);
      fprintf(stderr, "eventlfm bench: simulating %s (%d ms) ...\n", tok, op.duration_ms);
      char *sargv[] = {self, "simulate", si->name, "--out", si->dir, "--seed", seed,
                       "--duration-ms", dur, NULL};
      double wall = 0;
      int rc = cli_run_child(sargv, 0, logp, op.timeout_s, &wall, NULL, NULL);
      if (rc != 0)
        return cli_message("bench", CLI_FAIL, "simulate %s failed (exit %d); see %s", tok, rc, logp);
      char ev[PATH_MAX];
      cli_path_fmt(ev, sizeof ev, "%s/events.raw", si->dir);
      elfm_error err;
      elfm_error_clear(&err);
      if (cli_count_events(ev, &si->events, &si->t_first_us, &si->t_last_us, &err) != ELFM_OK)
        return cli_fail("bench", &err);
      fprintf(stderr, "eventlfm bench: %s: %lld events in %.1f s of simulation\n", tok,
              (long long)si->events, wall);
      /* calibrations with other plane spacings */
      char cp[PATH_MAX];
      cli_path_fmt(cp, sizeof cp, "%s/calib.json", si->dir);
      elfm_calib cal;
      if (elfm_calib_load(cp, &cal, &err) != ELFM_OK) return cli_fail("bench", &err);
      for (int k = 0; k < N_SWEEP; k++) {
        if (SWEEP[k].z_step_um <= 0) continue;
        elfm_calib c2 = cal;
        c2.z_step_um = SWEEP[k].z_step_um;
        char p2[PATH_MAX];
        cli_path_fmt(p2, sizeof p2, "%s/calib_dz%g.json", si->dir, SWEEP[k].z_step_um);
        if (elfm_calib_save(&c2, p2, &err) != ELFM_OK) return cli_fail("bench", &err);
      }
      if (!strncmp(si->name, "stage", 5)) {
        char tp[PATH_MAX];
        cli_path_fmt(tp, sizeof tp, "%s/truth.csv", si->dir);
        if (bench_truth_stage_velocity(tp, si->stage_v_um_per_ms, &err) != ELFM_OK)
          return cli_fail("bench", &err);
        si->is_stage = 1;
        fprintf(stderr, "eventlfm bench: %s: stage velocity from truth (%.4f, %.4f, %.4f) um/ms\n",
                tok, si->stage_v_um_per_ms[0], si->stage_v_um_per_ms[1], si->stage_v_um_per_ms[2]);
      }
      n_sc++;
    }
  }

  if (n_sc == 0) return cli_message("bench", CLI_USAGE, "--scenes: no scene named");

  /* Sweep. */
  struct point_result *pts = calloc(BENCH_MAX_POINTS * 4, sizeof *pts);
  if (!pts) return cli_message("bench", CLI_FAIL, "out of memory");
  int rc_out = CLI_OK;
  int n_pts = 0, n_total = 0;
  for (int s = 0; s < n_sc; s++)
    for (int k = 0, m = 0; k < N_SWEEP; k++)
      if ((!op.quick || SWEEP[k].quick) && (!op.max_points || m < op.max_points)) { n_total++; m++; }
  char host[128] = "unknown";
  gethostname(host, sizeof host - 1);
  {
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    size_t l = strlen(host);
    cli_path_fmt(host + l, sizeof host - l, ", %ld CPUs online", ncpu);
  }
  for (int s = 0; s < n_sc; s++) {
    struct scene_info *si = &sc[s];
    int n_here = 0;
    for (int k = 0; k < N_SWEEP; k++) {
      const struct sweep_point *sp = &SWEEP[k];
      if (op.quick && !sp->quick) continue;
      if (op.max_points && n_here >= op.max_points) break;
      n_here++;
      struct point_result *p = &pts[n_pts++];
      memset(p, 0, sizeof *p);
      p->scene = si->name;
      p->sp = sp;
      p->events = si->events;
      p->span_s = (double)(si->t_last_us - si->t_first_us) * 1e-6;
      p->score.f1 = p->score.alpha = p->score.beta = NAN;
      p->score.rmse_x_um = p->score.rmse_y_um = p->score.rmse_z_um = NAN;
      p->score.recall = p->score.precision = NAN;
      p->score.jaccard_tracks = p->score.jaccard_detections = NAN;
      p->events_per_s = p->volumes = p->volumes_per_s = p->rtf = NAN;
      for (int q = 0; q < 4; q++) p->stage_s[q] = NAN;
      char run[PATH_MAX], calib[PATH_MAX], ev[PATH_MAX], logp[PATH_MAX];
      cli_path_fmt(run, sizeof run, "%s/runs/%s_%02d", dir, si->name, k);
      if (cli_mkdir_p(run) != 0) { rc_out = cli_message("bench", CLI_FAIL, "cannot create %s", run); goto out; }
      if (sp->z_step_um > 0) cli_path_fmt(calib, sizeof calib, "%s/calib_dz%g.json", si->dir, sp->z_step_um);
      else cli_path_fmt(calib, sizeof calib, "%s/calib.json", si->dir);
      cli_path_fmt(ev, sizeof ev, "%s/events.raw", si->dir);
      cli_path_fmt(logp, sizeof logp, "%s/track.log", run);
      char *targv[14 + BENCH_MAX_ARGS + 1]; /* 14: the fixed arguments below */
      int na = 0;
      targv[na++] = self;
      targv[na++] = "track";
      targv[na++] = "--calib";
      targv[na++] = calib;
      targv[na++] = "--events";
      targv[na++] = ev;
      targv[na++] = "--out";
      const int out_at = na;
      targv[na++] = run;
      /* the planes axis: exactly the calibration's planes (track would
       * otherwise take every m-th of them, --plane-shift-px) */
      if (sp->z_step_um > 0) {
        targv[na++] = "--plane-shift-px";
        targv[na++] = "0";
      }
      /* each row measures its own setting: a setting that dims the peaks
       * (a median, a short tau) would otherwise make --blur-px auto start
       * again with the blur, a second change in the row */
      targv[na++] = "--blur-px";
      targv[na++] = "0";
      /* ... and a stage's rows smooth as a stage: track's --motion auto
       * chooses that on a stage after its first ~20 frames, but a setting
       * that blurs the tracks' velocities could keep a row per-track */
      if (si->is_stage) {
        targv[na++] = "--motion";
        targv[na++] = "stage";
      }
      for (int a = 0; sp->args[a]; a++) targv[na++] = (char *)sp->args[a];
      targv[na] = NULL;
      if (n_here == 1) {
        /* The scene's first point also runs once before, untimed, into
         * runs/SCENE_warmup: a scene's first run reads the binary and the
         * events into the page cache, and the defaults, first in the
         * sweep, came out up to a fifth slower than the same settings
         * given later in the same sweep (docs/bench.md, sixty-seventh
         * session). */
        char warm[PATH_MAX], wlog[PATH_MAX];
        double w_s, w_mb, w_cpu;
        cli_path_fmt(warm, sizeof warm, "%s/runs/%s_warmup", dir, si->name);
        cli_path_fmt(wlog, sizeof wlog, "%s/track.log", warm);
        if (cli_mkdir_p(warm) != 0) { rc_out = cli_message("bench", CLI_FAIL, "cannot create %s", warm); goto out; }
        targv[out_at] = warm;
        (void)cli_run_child(targv, 0, wlog, op.timeout_s, &w_s, &w_mb, &w_cpu);
        targv[out_at] = run;
      }
      int rc = cli_run_child(targv, 0, logp, op.timeout_s, &p->wall_s, &p->peak_rss_mb, &p->cpu_s);
      if (rc != 0) p->peak_rss_mb = NAN; /* a rejected run's memory means nothing */
      if (rc == 2) p->status = "unsupported";
      else if (rc == -2) p->status = "timeout";
      else if (rc != 0) p->status = "failed";
      else {
        p->status = "ok";
        p->events_per_s = (double)p->events / p->wall_s;
        p->rtf = p->span_s / p->wall_s;
        bench_summary_read(run, &p->volumes, p->stage_s);
        char truth[PATH_MAX], tracks[PATH_MAX], dets[PATH_MAX];
        cli_path_fmt(truth, sizeof truth, "%s/truth.csv", si->dir);
        cli_path_fmt(tracks, sizeof tracks, "%s/tracks.csv", run);
        cli_path_fmt(dets, sizeof dets, "%s/detections.csv", run);
        elfm_score_options so;
        elfm_score_options_default(&so);
        if (p->volumes > 0) so.n_frames_hint = (int64_t)p->volumes; /* frames 0..volumes-1 */
        if (si->is_stage) {
          so.have_stage = 1;
          memcpy(so.stage_v_um_per_ms, si->stage_v_um_per_ms, sizeof so.stage_v_um_per_ms);
        }
        elfm_calib cal;
        elfm_error err;
        elfm_error_clear(&err);
        if (elfm_calib_load(calib, &cal, &err) == ELFM_OK) elfm_score_options_set_calib(&so, &cal);
        if (elfm_score_files(truth, tracks, access(dets, R_OK) == 0 ? dets : NULL, &so,
                             &p->score, &err) != ELFM_OK) {
          char m[1200];
          fprintf(stderr, "eventlfm bench: scoring %s: %s\n", run,
                  elfm_error_format(&err, m, sizeof m));
          p->status = "score failed";
        }
        if (!(p->volumes >= 0)) p->volumes = p->score.n_frames;
        p->volumes_per_s = p->volumes / p->wall_s;
      }
      fprintf(stderr, "eventlfm bench: [%d/%d] %s %-15s %-20s %-11s %6.2f s  RTF %6.3f  F1 %.3f  alpha %.3f\n",
              n_pts, n_total, si->name, sp->axis, sp->setting, p->status, p->wall_s, p->rtf,
              p->score.f1, p->score.alpha);
    }
    bench_mark_pareto(pts, n_pts, si->name);
  }

  const char *comp_names[16];
  int n_comps = 0;
  if (op.components)
    bench_run_components(self, dir, sc[0].dir, op.quick, op.quick ? 180 : op.timeout_s,
                         comp_names, &n_comps);

  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/bench.csv", dir);
  if (bench_write_csv(p, pts, n_pts) != 0) { rc_out = cli_message("bench", CLI_FAIL, "cannot write %s", p); goto out; }
  int fig_ok = 1;
  if (op.figures) {
    if (bench_write_plot(dir, sc, n_sc, pts, n_pts, 120) != 0) {
      fprintf(stderr, "eventlfm bench: gnuplot failed; see %s/plot/gnuplot.log\n", dir);
      fig_ok = 0;
    }
    fprintf(stderr, "eventlfm bench: Fig. S4 reconstructions ...\n");
    if (bench_fig_s4(self, dir, &sc[0], op.timeout_s) != 0) fig_ok = 0;
  }
  if (bench_write_md(dir, &op, sc, n_sc, pts, n_pts, comp_names, n_comps, host) != 0)
    { rc_out = cli_message("bench", CLI_FAIL, "cannot write %s/bench.md", dir); goto out; }

  /* Short summary on stdout: the best point per scene. */
  int n_ok = 0;
  for (int i = 0; i < n_pts; i++) n_ok += !strcmp(pts[i].status, "ok");
  printf("eventlfm bench: %d of %d points ran; results in %s/bench.md, bench.csv%s\n", n_ok, n_pts,
         dir, op.figures ? ", bench_error_vs_speed.png, fig_s4.png" : "");
  for (int s = 0; s < n_sc; s++) {
    /* The most accurate point (alpha), and the fastest whose alpha is
     * within 0.02 of it: the fastest point alone is often one that found
     * nothing (a median filter that removes every sparse object runs fast). */
    int best = -1, fast = -1;
    for (int i = 0; i < n_pts; i++)
      if (!strcmp(pts[i].scene, sc[s].name) && !strcmp(pts[i].status, "ok") &&
          (best < 0 || pts[i].score.alpha > pts[best].score.alpha))
        best = i;
    for (int i = 0; best >= 0 && i < n_pts; i++)
      if (!strcmp(pts[i].scene, sc[s].name) && !strcmp(pts[i].status, "ok") &&
          pts[i].score.alpha >= pts[best].score.alpha - 0.02 &&
          (fast < 0 || pts[i].rtf > pts[fast].rtf))
        fast = i;
    if (best >= 0)
      printf("  %s: best alpha '%s' %.3f (F1 %.3f, RTF %.3f); fastest within 0.02 of it '%s' "
             "RTF %.3f (%.2f Mev/s), alpha %.3f\n",
             sc[s].name, pts[best].sp->setting, pts[best].score.alpha, pts[best].score.f1,
             pts[best].rtf, pts[fast].sp->setting, pts[fast].rtf,
             pts[fast].events_per_s * 1e-6, pts[fast].score.alpha);
  }
  if (n_ok == 0) {
    rc_out = cli_message("bench", CLI_FAIL, "no sweep point ran; see %s/runs/*/track.log", dir);
    goto out;
  }
  if (!fig_ok) cli_message("bench", CLI_OK, "some figures are missing (see the logs in %s)", dir);
out:
  free(pts);
  return rc_out;
}
