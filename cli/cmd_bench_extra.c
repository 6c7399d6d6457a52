/* cmd_bench_extra.c — the runs of `eventlfm bench` beside the sweep: the
 * Fig. S4 reconstructions and the component benchmarks (cmd_bench.h). Both
 * run child processes with their own logs; a failure costs a figure or a
 * log, never the sweep. */
#include <dirent.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cmd_bench.h"

/* Fig. S4: time surface vs accumulation at 1, 5 and 10 ms. `eventlfm recon
 * --save-mips` writes depth-coded MIPs; we take the last one of each run and
 * let gnuplot put them side by side (rgbimage), rather than compose PNGs
 * ourselves. */

static int newest_png(const char *dir, char *out, size_t n)
{
  DIR *d = opendir(dir);
  if (!d) return -1;
  struct dirent *e;
  char best[256] = "";
  while ((e = readdir(d))) {
    size_t l = strlen(e->d_name);
    if (l > 4 && !strcmp(e->d_name + l - 4, ".png") && strcmp(e->d_name, best) > 0 &&
        l < sizeof best)
      memcpy(best, e->d_name, l + 1);
  }
  closedir(d);
  if (!best[0]) return -1;
  cli_path_fmt(out, n, "%s/%s", dir, best);
  return 0;
}

int bench_fig_s4(const char *self, const char *dir, const struct scene_info *si,
                 double timeout_s)
{
  static const int dts_ms[3] = {1, 5, 10};
  static const char *reprs[2] = {"exp", "count"};
  char pngs[2][3][PATH_MAX];
  /* the same window end for every panel: 1 ms before the recording ends */
  int64_t t_end = si->t_last_us - 1000;
  for (int r = 0; r < 2; r++)
    for (int k = 0; k < 3; k++) {
      char out[PATH_MAX], calib[PATH_MAX], ev[PATH_MAX], dt[32], from[32], to[32], logp[PATH_MAX];
      cli_path_fmt(out, sizeof out, "%s/fig_s4/%s_%dms", dir, reprs[r], dts_ms[k]);
      if (cli_mkdir_p(out) != 0) return -1;
      cli_path_fmt(calib, sizeof calib, "%s/calib.json", si->dir);
      cli_path_fmt(ev, sizeof ev, "%s/events.raw", si->dir);
      cli_path_fmt(dt, sizeof dt, "%d", dts_ms[k] * 1000);
      /* exactly one window [t_end - dt, t_end): one MIP per run. The time
       * surface decays with tau = dt, so that a longer window also shows a
       * longer history (with a fixed 1 ms tau all three would look alike). */
      cli_path_fmt(from, sizeof from, "%lld", (long long)(t_end - dts_ms[k] * 1000));
      cli_path_fmt(to, sizeof to, "%lld", (long long)t_end);
      cli_path_fmt(logp, sizeof logp, "%s/recon.log", out);
      char *argv[] = {(char *)self, "recon", "--calib", calib, "--events", ev, "--out", out,
                      "--repr", (char *)reprs[r], "--dt-us", dt, "--tau-us", dt, "--from-us",
                      from, "--to-us", to, "--save-mips", "--quiet", NULL};
      int rc = cli_run_child(argv, 0, logp, timeout_s, NULL, NULL, NULL);
      if (rc != 0 || newest_png(out, pngs[r][k], PATH_MAX) != 0) {
        /* MIPs may sit in a sub-directory */
        char sub[PATH_MAX];
        cli_path_fmt(sub, sizeof sub, "%s/mips", out);
        if (rc != 0 || newest_png(sub, pngs[r][k], PATH_MAX) != 0) {
          fprintf(stderr, "eventlfm bench: Fig. S4 panel %s %d ms: recon %s (see %s)\n",
                  reprs[r], dts_ms[k], rc != 0 ? "failed" : "wrote no PNG", logp);
          return -1;
        }
      }
    }
  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/fig_s4.gnuplot", dir);
  FILE *g = fopen(p, "w");
  if (!g) return -1;
  fprintf(g, "set terminal pngcairo size 1500,1000 font 'sans,11'\nset output '%s/fig_s4.png'\n"
             "set multiplot layout 2,3 title 'time surface (top) vs accumulation (bottom): "
             "MIPs at 1, 5, 10 ms'\nunset key\nunset tics\nunset border\nset size ratio -1\n",
          dir);
  for (int r = 0; r < 2; r++)
    for (int k = 0; k < 3; k++)
      fprintf(g, "set title '%s, %d ms'\nplot '%s' binary filetype=png with rgbimage\n",
              r == 0 ? "exp time surface" : "counts", dts_ms[k], pngs[r][k]);
  fprintf(g, "unset multiplot\n");
  fclose(g);
  char logp[PATH_MAX];
  cli_path_fmt(logp, sizeof logp, "%s/fig_s4/gnuplot.log", dir);
  char *argv[] = {"gnuplot", p, NULL};
  return cli_run_child(argv, 1, logp, timeout_s, NULL, NULL, NULL) == 0 ? 0 : -1;
}

/* The component benchmarks of the other modules, with the arguments that
 * keep --quick short (their defaults are sized for a careful measurement).
 * They take positional or long options of their own and not all answer
 * --help, so the arguments are fixed here (from each program's header
 * comment). A program that is not built is reported and skipped. */
struct component {
  const char *name;
  const char *what;
  int quick_skip;               /* too long for --quick even when shortened */
  const char *quick_args[6];    /* NULL-terminated */
  const char *full_args[6];     /* without --quick (NULL-terminated) */
};
static const struct component COMPONENTS[] = {
    {"bench_decode", "EVT3/EVT2/DAT decode vs the memory-read ceiling", 0,
     {"--events", "10000000", "--reps", "3", NULL}, {NULL}},
    {"bench_refocus", "sparse vs dense refocusing, 1 and 2 threads", 0,
     {"--ms", "20", "--reps", "2", NULL}, {NULL}},
    {"bench_link", "FLANN linking vs brute force, 100/1000/10000 objects", 0, {"10", NULL},
     {NULL}},
    {"bench_smooth", "Ceres smoothing per 1000-point track", 0, {"1", NULL}, {"1", NULL}},
    {"bench_simulate", "simulator speed", 0, {"flow", "100", "100", NULL}, {NULL}},
    {"bench_pipeline_score", "Hungarian solver and scoring", 0, {"--quick", NULL}, {NULL}},
    /* {calib} and {events}: the first scene's files */
    {"bench_peaks", "3D peak detection on refocused volumes", 0,
     {"{calib}", "{events}", "50", "3", NULL}, {"{calib}", "{events}", NULL}},
};
#define N_COMPONENTS ((int)(sizeof COMPONENTS / sizeof COMPONENTS[0]))

int bench_run_components(const char *self, const char *dir, const char *scene_dir, int quick,
                         double timeout_s, const char **names, int *n_out)
{
  char calib[PATH_MAX], events[PATH_MAX];
  cli_path_fmt(calib, sizeof calib, "%s/calib.json", scene_dir);
  cli_path_fmt(events, sizeof events, "%s/events.raw", scene_dir);
  char bdir[PATH_MAX];
  cli_path_fmt(bdir, sizeof bdir, "%s", self);
  char *slash = strrchr(bdir, '/');
  if (slash) *slash = '\0';
  char cdir[PATH_MAX];
  cli_path_fmt(cdir, sizeof cdir, "%s/components", dir);
  if (cli_mkdir_p(cdir) != 0) return -1;
  int n = 0;
  for (int i = 0; i < N_COMPONENTS; i++) {
    const struct component *cp = &COMPONENTS[i];
    char exe[PATH_MAX], logp[PATH_MAX];
    cli_path_fmt(exe, sizeof exe, "%s/bench/%s", bdir, cp->name);
    cli_path_fmt(logp, sizeof logp, "%s/%s.txt", cdir, cp->name);
    if (access(exe, X_OK) != 0) {
      fprintf(stderr, "eventlfm bench: %s not built (%s), skipped\n", cp->name, exe);
      continue;
    }
    if (quick && cp->quick_skip) {
      FILE *f = fopen(logp, "w");
      if (f) {
        fprintf(f, "[eventlfm bench --quick: skipped (too long for --quick); run %s]\n", exe);
        fclose(f);
      }
      names[n++] = cp->name;
      continue;
    }
    char *argv[8];
    int na = 0;
    char shown[3 * PATH_MAX] = "";
    argv[na++] = exe;
    const char *const *args = quick ? cp->quick_args : cp->full_args;
    for (int a = 0; args[a] && na < 7; a++) {
      const char *arg = !strcmp(args[a], "{calib}") ? calib
                        : !strcmp(args[a], "{events}") ? events : args[a];
      argv[na++] = (char *)arg;
      size_t l = strlen(shown);
      cli_path_fmt(shown + l, sizeof shown - l, " %s", arg);
    }
    argv[na] = NULL;
    fprintf(stderr, "eventlfm bench: component %s%s (%s) ...\n", cp->name, shown, cp->what);
    double wall = 0;
    int rc = cli_run_child(argv, 0, logp, timeout_s, &wall, NULL, NULL);
    FILE *f = fopen(logp, "a");
    if (f) {
      fprintf(f, "[eventlfm bench: `%s%s` (%s) exited %d after %.1f s%s]\n", cp->name, shown,
              cp->what, rc, wall, rc == -2 ? " (killed: time limit)" : "");
      fclose(f);
    }
    names[n++] = cp->name;
  }
  *n_out = n;
  return 0;
}
