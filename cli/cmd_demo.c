/* cmd_demo.c — eventlfm demo: simulate a short flow scene, track it, score
 * it, draw it, and print a short table of speed and error.
 *
 * It chains the program's own subcommands in process (cmd_simulate,
 * cmd_track, cmd_recon: the same code paths a user runs by hand) and scores
 * with the library. The built-in scenes live inside the library, so the demo
 * needs no file from the source tree and works from any directory.
 */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli.h"
#include "elfm_tracker.h"


struct demo_opts {
  const char *out;
  const char *scene;
  int duration_ms;
  int64_t seed;
  int plots;
};

static void demo_usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm demo [--out DIR] [--scene flow] [--duration-ms 200] [--seed 1]\n"
          "                     [--no-plots]\n"
          "\n"
          "Simulates a short scene of the built-in simulator (default: flow, beads moving in\n"
          "3D), runs the tracking pipeline on it (eventlfm track), scores the result against\n"
          "the simulator's truth (SPEC 7), writes depth-coded MIP PNGs (eventlfm recon\n"
          "--save-mips) and a track plot (gnuplot), and prints speed and error, the error\n"
          "also by the truth's depth (recall and alpha at |z| 0-20, 20-40, 40-60 and beyond\n"
          "60 um: score --by-depth).\n"
          "Output directory: DIR (default eventlfm_demo) with sim/, track/, recon/mips/, tracks.png.\n");
}

/* Run one of our subcommands in process with a fresh getopt state. */
static int run_sub(int (*fn)(int, char **), char **argv)
{
  int argc = 0;
  while (argv[argc]) argc++;
  optind = 0; /* glibc: 0 re-initialises getopt completely */
  fflush(stdout);
  int rc = fn(argc, argv);
  fflush(stdout);
  optind = 0;
  return rc;
}

/* Track plot: x-y and x-z of the tracks over the truth, by gnuplot (the
 * project draws plots with gnuplot rather than a PNG writer of its own). */
static int track_plot(const char *dir)
{
  char script[PATH_MAX], logp[PATH_MAX];
  cli_path_fmt(script, sizeof script, "%s/tracks.gnuplot", dir);
  FILE *g = fopen(script, "w");
  if (!g) return -1;
  fprintf(g,
          "set datafile separator ','\n"
          "set terminal pngcairo size 1200,560 font 'sans,10'\n"
          "set output '%s/tracks.png'\n"
          "set multiplot layout 1,2 title 'eventlfm demo: tracks (colour = time) over truth (grey)'\n"
          "set key off\nset grid\nset size ratio -1\nset cblabel 'time (ms)'\n"
          "set xlabel 'x (um)'\nset ylabel 'y (um)'\n"
          "plot '%s/sim/truth.csv' using 3:4 every 5 with points pt 7 ps 0.15 lc rgb '#c8c8c8', \\\n"
          "     '%s/track/tracks.csv' using 4:5:($3/1000.0) with points pt 7 ps 0.3 lc palette\n"
          "set size noratio\nset xlabel 'x (um)'\nset ylabel 'z (um)'\n"
          "plot '%s/sim/truth.csv' using 3:5 every 5 with points pt 7 ps 0.15 lc rgb '#c8c8c8', \\\n"
          "     '%s/track/tracks.csv' using 4:6:($3/1000.0) with points pt 7 ps 0.3 lc palette\n"
          "unset multiplot\n",
          dir, dir, dir, dir, dir);
  fclose(g);
  cli_path_fmt(logp, sizeof logp, "%s/tracks_gnuplot.log", dir);
  char *argv[] = {"gnuplot", script, NULL};
  return cli_run_child(argv, 1, logp, 0, NULL, NULL, NULL) == 0 ? 0 : -1;
}

/* The tracker's volume count from its summary.json (counts.volumes), or 0:
 * the run's frames are 0 .. volumes - 1, which scoring needs to count truth
 * in frames where nothing was detected at the start or the end. */
static int64_t summary_volumes(const char *track_dir)
{
  char p[PATH_MAX];
  if (cli_path_fmt(p, sizeof p, "%s/summary.json", track_dir) != 0) return 0;
  /* A summary longer than 4 MB (thousands of tracks) gives no hint: the
   * scorer then counts from the files' rows alone. */
  char *text = cli_read_text(p, (1 << 22) - 1);
  if (!text) return 0;
  cJSON *o = cJSON_Parse(text);
  free(text);
  const cJSON *c = cJSON_GetObjectItemCaseSensitive(o, "counts");
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(c, "volumes");
  int64_t vol = cJSON_IsNumber(v) && v->valuedouble > 0 ? (int64_t)v->valuedouble : 0;
  cJSON_Delete(o);
  return vol;
}

/* Recall and alpha by the truth's depth, bands of 20 um and all beyond
 * 60 um together (score --by-depth): a Fourier LFM sees less out of focus,
 * and this shows where. */
static void depth_line(const elfm_score_result *r)
{
  if (r->n_depth_bands < 4) return;
  printf("  %-34s", "recall / alpha by |z| (um)");
  for (int k = 0; k < 4; k++) {
    int64_t n = 0, tp = 0;
    double a = 0;
    for (int b = k; b < (k < 3 ? k + 1 : r->n_depth_bands); b++) {
      const elfm_score_band *d = &r->depth_bands[b];
      if (d->n_truth_points == 0) continue;
      n += d->n_truth_points;
      tp += d->n_true_positives;
      a += (double)d->n_truth_points * d->alpha_tracks;
    }
    if (k < 3) printf(" %s%d-%d", k ? "  " : "", 20 * k, 20 * k + 20);
    else printf("   60+");
    if (n > 0) printf(" %.2f / %.2f", (double)tp / (double)n, a / (double)n);
    else printf(" -");
  }
  printf("\n");
}

int cmd_demo(int argc, char **argv)
{
  enum { OPT_OUT = 256, OPT_SCENE, OPT_DUR, OPT_SEED, OPT_NOPLOTS };
  static const struct option longopts[] = {
      {"out", required_argument, NULL, OPT_OUT},
      {"scene", required_argument, NULL, OPT_SCENE},
      {"duration-ms", required_argument, NULL, OPT_DUR},
      {"seed", required_argument, NULL, OPT_SEED},
      {"no-plots", no_argument, NULL, OPT_NOPLOTS},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0}};
  struct demo_opts op = {"eventlfm_demo", "flow", 200, 1, 1};
  optind = 1;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
    switch (c) {
    case 'h': demo_usage(stdout); return CLI_OK;
    case OPT_OUT: op.out = optarg; break;
    case OPT_SCENE: op.scene = optarg; break;
    case OPT_DUR:
      if (!cli_parse_int("demo", "--duration-ms", optarg, &op.duration_ms)) return CLI_USAGE;
      if (op.duration_ms < 20 || op.duration_ms > 60000)
        return cli_message("demo", CLI_USAGE, "--duration-ms must be 20..60000");
      break;
    case OPT_SEED:
      if (!cli_parse_int64("demo", "--seed", optarg, &op.seed)) return CLI_USAGE;
      /* simulate's own rule, here before anything runs (it failed as the
       * simulation's error, exit 1) */
      if (op.seed < 0) return cli_message("demo", CLI_USAGE, "--seed must be >= 0");
      break;
    case OPT_NOPLOTS: op.plots = 0; break;
    default:
      cli_message("demo", CLI_USAGE, "unknown option or missing value: '%s'", argv[optind - 1]);
      demo_usage(stderr);
      return CLI_USAGE;
    }
  }
  if (optind < argc)
    return cli_message("demo", CLI_USAGE, "unexpected argument '%s'", argv[optind]);

  char dir[PATH_MAX];
  /* the longest file of the four steps, as given (made absolute below, a
   * relative --out grows by the working directory: the steps then refuse) */
  if (!cli_out_fits("demo", op.out, "/track/tracks_trackmate.xml")) return CLI_FAIL;
  if (cli_mkdir_p(op.out) != 0 || !realpath(op.out, dir)) /* and its parents */
    return cli_message("demo", CLI_FAIL, "cannot create %s: %s", op.out, strerror(errno));
  char sim[PATH_MAX], trk[PATH_MAX], mips[PATH_MAX], calib[PATH_MAX], ev[PATH_MAX];
  cli_path_fmt(sim, sizeof sim, "%s/sim", dir);
  cli_path_fmt(trk, sizeof trk, "%s/track", dir);
  cli_path_fmt(mips, sizeof mips, "%s/recon", dir); /* recon writes recon/mips/ */
  cli_path_fmt(calib, sizeof calib, "%s/calib.json", sim);
  cli_path_fmt(ev, sizeof ev, "%s/events.raw", sim);
  if (cli_mkdir_p(sim) || cli_mkdir_p(trk) || cli_mkdir_p(mips))
    return cli_message("demo", CLI_FAIL, "cannot create directories in %s", dir);

  /* 1. simulate */
  char dur[32], seed[32];
  cli_path_fmt(dur, sizeof dur, "%d", op.duration_ms);
  cli_path_fmt(seed, sizeof seed, "%lld", (long long)op.seed);
  fprintf(stderr, "eventlfm demo: [1/4] simulating %s, %d ms ...\n", op.scene, op.duration_ms);
  double t0 = cli_now_s();
  char *sargv[] = {"simulate", (char *)op.scene, "--out", sim, "--seed", seed,
                   "--duration-ms", dur, NULL};
  if (run_sub(cmd_simulate, sargv) != CLI_OK)
    return cli_message("demo", CLI_FAIL, "simulation failed");
  double sim_s = cli_now_s() - t0;
  int64_t n_ev = 0, t_first = 0, t_last = 0;
  elfm_error err;
  elfm_error_clear(&err);
  if (cli_count_events(ev, &n_ev, &t_first, &t_last, &err) != ELFM_OK)
    return cli_fail("demo", &err);
  double span_s = (double)(t_last - t_first) * 1e-6;

  /* 2. track */
  fprintf(stderr, "eventlfm demo: [2/4] tracking %lld events ...\n", (long long)n_ev);
  char *targv[] = {"track", "--calib", calib, "--events", ev, "--out", trk, NULL};
  t0 = cli_now_s();
  if (run_sub(cmd_track, targv) != CLI_OK)
    return cli_message("demo", CLI_FAIL, "tracking failed");
  double track_s = cli_now_s() - t0;

  /* 3. score */
  fprintf(stderr, "eventlfm demo: [3/4] scoring ...\n");
  char truth[PATH_MAX], tracks[PATH_MAX], dets[PATH_MAX];
  cli_path_fmt(truth, sizeof truth, "%s/truth.csv", sim);
  cli_path_fmt(tracks, sizeof tracks, "%s/tracks.csv", trk);
  cli_path_fmt(dets, sizeof dets, "%s/detections.csv", trk);
  elfm_calib cal;
  if (elfm_calib_load(calib, &cal, &err) != ELFM_OK) return cli_fail("demo", &err);
  elfm_score_options so;
  elfm_score_options_default(&so);
  elfm_score_options_set_calib(&so, &cal);
  so.n_frames_hint = summary_volumes(trk);
  so.depth_band_um = 20; /* where out of focus the run can be trusted */
  elfm_score_result r;
  if (elfm_score_files(truth, tracks, access(dets, R_OK) == 0 ? dets : NULL, &so, &r, &err) !=
      ELFM_OK)
    return cli_fail("demo", &err);

  /* 4. pictures: MIPs of the last 10 ms, and the track plot */
  int pics_ok = 1;
  if (op.plots) {
    fprintf(stderr, "eventlfm demo: [4/4] MIPs and track plot ...\n");
    char from[32], to[32];
    int64_t win = span_s > 0.02 ? 10000 : 2000;
    cli_path_fmt(from, sizeof from, "%lld", (long long)(t_last - win));
    cli_path_fmt(to, sizeof to, "%lld", (long long)t_last);
    char *rargv[] = {"recon", "--calib", calib, "--events", ev, "--out", mips, "--from-us", from,
                     "--to-us", to, "--save-mips", "--quiet", NULL};
    if (run_sub(cmd_recon, rargv) != CLI_OK) {
      cli_message("demo", CLI_OK, "recon --save-mips failed: no MIP PNGs");
      pics_ok = 0;
    }
    if (track_plot(dir) != 0) {
      cli_message("demo", CLI_OK, "gnuplot failed: no tracks.png (see %s/tracks_gnuplot.log)", dir);
      pics_ok = 0;
    }
  }

  double rtf = track_s > 0 ? span_s / track_s : NAN;
  printf("\neventlfm demo: scene %s, %d ms, seed %lld\n", op.scene, op.duration_ms,
         (long long)op.seed);
  printf("  %-34s %12lld  (%.2f Mev/s of recording)\n", "events", (long long)n_ev,
         span_s > 0 ? (double)n_ev / span_s * 1e-6 : 0.0);
  printf("  %-34s %12.2f s\n", "simulation", sim_s);
  printf("  %-34s %12.2f s  (%.2f Mev/s processed)\n", "tracking (events -> tracks files)",
         track_s, track_s > 0 ? (double)n_ev / track_s * 1e-6 : 0.0);
  printf("  %-34s %12.3f  (%s real time)\n", "real-time factor (span / wall)", rtf,
         rtf >= 1 ? "faster than" : "slower than");
  printf("  %-34s %12.3f  (recall %.3f, precision %.3f)\n", "detection F1", r.f1, r.recall,
         r.precision);
  printf("  %-34s %8.2f / %.2f / %.2f um\n", "RMSE x / y / z", r.rmse_x_um, r.rmse_y_um,
         r.rmse_z_um);
  printf("  %-34s %12.3f / %.3f\n", "ISBI alpha / beta", r.alpha, r.beta);
  printf("  %-34s %d paired, %d missed, %d spurious\n", "tracks (of truth / candidates)",
         r.n_paired_tracks, r.n_missed_tracks, r.n_spurious_tracks);
  depth_line(&r);
  printf("  outputs: %s/{sim,track%s}\n", dir, op.plots && pics_ok ? ",recon/mips,tracks.png" : "");
  return CLI_OK;
}
