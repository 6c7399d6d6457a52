/* cmd_bench.c — eventlfm bench: sweep the pipeline's settings on simulated
 * scenes and put speed against error (issue 7; docs/bench.md).
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
#include <dirent.h>
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli.h"
#include "elfm_tracker.h"


#define BENCH_MAX_ARGS 8
#define BENCH_MAX_POINTS 64
/* The most of a summary.json or a component's log that is read back. */
#define BENCH_MAX_TEXT (1L << 26)

struct bench_opts {
  int quick;
  const char *out;
  char scenes[256];
  int duration_ms;
  int64_t seed;
  int components, figures;
  double timeout_s;
  int max_points; /* 0: all; else only the first N points per scene (smoke tests) */
};

/* One sweep point: extra arguments to `eventlfm track`, or a calibration
 * with another plane spacing. */
struct sweep_point {
  const char *axis, *setting;
  const char *args[BENCH_MAX_ARGS]; /* NULL-terminated */
  double z_step_um;                 /* 0: the scene's calibration */
  int quick;                        /* 1: part of --quick */
};

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
    {"threads", "1 thread", {"--threads", "1", NULL}, 0, 1},
    {"threads", "2 threads", {"--threads", "2", NULL}, 0, 1},
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

struct point_result {
  const char *scene;
  const struct sweep_point *sp;
  const char *status;   /* "ok", "unsupported", "failed", "timeout", "score failed" */
  double wall_s, peak_rss_mb;
  double cpu_s; /* user + system time of the child, all its threads */
  int64_t events;
  double span_s, events_per_s, volumes, volumes_per_s, rtf;
  elfm_score_result score;
  int pareto_f1, pareto_alpha;
  double stage_s[4]; /* the tracker's own timing: recon, peaks, link, smooth (summary.json) */
};
static const char *const STAGE_KEYS[4] = {"recon_s", "peaks_s", "link_s", "smooth_s"};

struct scene_info {
  char name[64];
  char dir[PATH_MAX];
  int64_t events, t_first_us, t_last_us;
  int is_stage;              /* a stage scene: score the mean velocity too */
  double stage_v_um_per_ms[3];
};

/* ---------------------------------------------------------------------- */
/* The run's files: this program's path, the tracker's summary, the truth */

static int self_exe(char *buf, size_t size)
{
  ssize_t n = readlink("/proc/self/exe", buf, size - 1);
  if (n <= 0) return -1;
  buf[n] = '\0';
  return 0;
}

/* Depth-first search of a numeric key in a JSON tree. */
static const cJSON *json_find(const cJSON *o, const char *key)
{
  if (!o) return NULL;
  for (const cJSON *c = o->child; c; c = c->next) {
    if (c->string && !strcmp(c->string, key) && cJSON_IsNumber(c)) return c;
    const cJSON *r = json_find(c, key);
    if (r) return r;
  }
  return NULL;
}

/* Numbers from the tracker's summary.json: the volume count (first of a few
 * plausible key names) and the per-stage seconds; -1 / NaN when absent. */
static void summary_read(const char *run_dir, double *volumes, double stage_s[4])
{
  *volumes = -1;
  for (int k = 0; k < 4; k++) stage_s[k] = NAN;
  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/summary.json", run_dir);
  char *text = cli_read_text(p, BENCH_MAX_TEXT);
  if (!text) return;
  cJSON *o = cJSON_Parse(text);
  free(text);
  static const char *keys[] = {"volumes", "n_volumes", "frames", "n_frames"};
  for (size_t i = 0; i < sizeof keys / sizeof keys[0] && *volumes < 0; i++) {
    const cJSON *n = json_find(o, keys[i]);
    if (n) *volumes = n->valuedouble;
  }
  for (int k = 0; k < 4; k++) {
    const cJSON *n = json_find(o, STAGE_KEYS[k]);
    if (n) stage_s[k] = n->valuedouble;
  }
  cJSON_Delete(o);
}

/* A stage scene moves every bead with the stage: its velocity is the mean
 * over truth ids of (last - first position) / (last - first time). Ids are
 * per pass through the field, so each is one straight segment. */
static elfm_status truth_stage_velocity(const char *truth_csv, double v[3], elfm_error *err)
{
  elfm_table *t = NULL;
  elfm_status s = elfm_table_load_csv(truth_csv, &t, err);
  if (s != ELFM_OK) return s;
  static const char *const names[] = {"id", "t_us", "x_um", "y_um", "z_um"};
  int c[5];
  if ((s = elfm_table_require(t, names, 5, c, err)) != ELFM_OK) { elfm_table_free(t); return s; }
  /* first and last row of each id, ids in order of appearance (a stage
   * scene has a few hundred passes; more are not needed for a mean) */
  enum { MAX_IDS = 4096 };
  double *ids = malloc(MAX_IDS * sizeof *ids);
  size_t *first = malloc(MAX_IDS * sizeof *first), *last = malloc(MAX_IDS * sizeof *last);
  if (!ids || !first || !last) {
    free(ids);
    free(first);
    free(last);
    elfm_table_free(t);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  }
  int n_ids = 0;
  for (size_t r = 0; r < t->n_rows; r++) {
    double id = elfm_table_get(t, r, c[0]);
    int k = 0;
    while (k < n_ids && ids[k] != id) k++;
    if (k == n_ids) {
      if (n_ids == MAX_IDS) break;
      ids[n_ids] = id;
      first[n_ids] = r;
      n_ids++;
    }
    last[k] = r;
  }
  double sum[3] = {0, 0, 0};
  int n = 0;
  for (int k = 0; k < n_ids; k++) {
    double dt_ms = (elfm_table_get(t, last[k], c[1]) - elfm_table_get(t, first[k], c[1])) * 1e-3;
    if (!(dt_ms > 0)) continue;
    for (int a = 0; a < 3; a++)
      sum[a] += (elfm_table_get(t, last[k], c[2 + a]) - elfm_table_get(t, first[k], c[2 + a])) / dt_ms;
    n++;
  }
  elfm_table_free(t);
  free(ids);
  free(first);
  free(last);
  if (n == 0)
    return elfm_error_set(err, ELFM_ERR_FORMAT, truth_csv, -1, "no moving object in the truth");
  for (int a = 0; a < 3; a++) v[a] = sum[a] / n;
  return ELFM_OK;
}

/* ---------------------------------------------------------------------- */
/* Pareto fronts: maximise the real-time factor, minimise the error. */

static double err_f1(const struct point_result *p) { return 1.0 - p->score.f1; }
static double err_alpha(const struct point_result *p) { return 1.0 - p->score.alpha; }

static void mark_pareto(struct point_result *pts, int n, const char *scene,
                        double (*err)(const struct point_result *), int which)
{
  for (int i = 0; i < n; i++) {
    struct point_result *p = &pts[i];
    if (strcmp(p->scene, scene) || strcmp(p->status, "ok") || !isfinite(err(p))) continue;
    int dominated = 0;
    for (int j = 0; j < n && !dominated; j++) {
      const struct point_result *q = &pts[j];
      if (j == i || strcmp(q->scene, scene) || strcmp(q->status, "ok") || !isfinite(err(q)))
        continue;
      if (q->rtf >= p->rtf && err(q) <= err(p) && (q->rtf > p->rtf || err(q) < err(p)))
        dominated = 1;
    }
    if (which == 0) p->pareto_f1 = !dominated;
    else p->pareto_alpha = !dominated;
  }
}

/* ---------------------------------------------------------------------- */
/* Writers */

static void fmt_num(char *buf, size_t n, const char *fmt, double v)
{
  if (isfinite(v)) cli_path_fmt(buf, n, fmt, v);
  else cli_path_fmt(buf, n, "%s", "");
}

static void join_args(const struct sweep_point *sp, char *buf, size_t n)
{
  buf[0] = '\0';
  for (int a = 0; sp->args[a]; a++) {
    size_t l = strlen(buf);
    cli_path_fmt(buf + l, n - l, "%s%s", a ? " " : "", sp->args[a]);
  }
  if (sp->z_step_um > 0) {
    size_t l = strlen(buf);
    cli_path_fmt(buf + l, n - l, "%scalib z step %g um", buf[0] ? " " : "", sp->z_step_um);
  }
}

static int write_csv(const char *path, const struct point_result *pts, int n)
{
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fprintf(f, "scene,axis,setting,args,status,wall_s,events,span_s,events_per_s,volumes,"
             "volumes_per_s,realtime_factor,peak_rss_mb,f1,recall,precision,rmse_x_um,rmse_y_um,"
             "rmse_z_um,alpha,beta,jaccard_tracks,jaccard_detections,pareto_f1,pareto_alpha,"
             "recon_s,peaks_s,link_s,smooth_s,stage_velocity_rel_error,cpu_s,realtime_factor_cpu\n");
  for (int i = 0; i < n; i++) {
    const struct point_result *p = &pts[i];
    char args[256];
    join_args(p->sp, args, sizeof args);
    double v[] = {p->wall_s, (double)p->events, p->span_s, p->events_per_s, p->volumes,
                  p->volumes_per_s, p->rtf, p->peak_rss_mb, p->score.f1, p->score.recall,
                  p->score.precision, p->score.rmse_x_um, p->score.rmse_y_um, p->score.rmse_z_um,
                  p->score.alpha, p->score.beta, p->score.jaccard_tracks,
                  p->score.jaccard_detections};
    fprintf(f, "%s,%s,%s,%s,%s", p->scene, p->sp->axis, p->sp->setting, args, p->status);
    for (size_t k = 0; k < sizeof v / sizeof v[0]; k++) {
      char b[64];
      fmt_num(b, sizeof b, "%.6g", v[k]);
      fprintf(f, ",%s", b);
    }
    fprintf(f, ",%d,%d", p->pareto_f1, p->pareto_alpha);
    for (int k = 0; k < 4; k++) {
      char b[64];
      fmt_num(b, sizeof b, "%.4g", p->stage_s[k]);
      fprintf(f, ",%s", b);
    }
    char b[64];
    fmt_num(b, sizeof b, "%.5g", p->score.has_stage ? p->score.stage_rel_error : NAN);
    fprintf(f, ",%s", b);
    fmt_num(b, sizeof b, "%.5g", p->cpu_s);
    fprintf(f, ",%s", b);
    fmt_num(b, sizeof b, "%.5g", p->cpu_s > 0 ? p->span_s / p->cpu_s : NAN);
    fprintf(f, ",%s\n", b);
  }
  return fclose(f) == 0 ? 0 : -1;
}

static void md_component(FILE *f, const char *dir, const char *name)
{
  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/components/%s.txt", dir, name);
  char *t = cli_read_text(p, BENCH_MAX_TEXT);
  if (!t) return;
  fprintf(f, "\n### %s\n\n```\n%s%s```\n", name, t, (t[0] && t[strlen(t) - 1] != '\n') ? "\n" : "");
  free(t);
}

static int write_md(const char *dir, const struct bench_opts *op, const struct scene_info *sc,
                    int n_sc, const struct point_result *pts, int n, const char *const *comps,
                    int n_comps, const char *host)
{
  char path[PATH_MAX];
  cli_path_fmt(path, sizeof path, "%s/bench.md", dir);
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fprintf(f, "# eventlfm bench%s\n\n", op->quick ? " --quick" : "");
  fprintf(f, "Machine: %s. Every point runs `eventlfm track` as a child process; wall time "
             "includes process start, reading the events and writing all outputs. Real-time "
             "factor = recording span / wall time (>= 1: faster than the camera); RTF (CPU) = "
             "recording span / CPU time of the run, all threads (less sensitive to other load "
             "on the machine). Errors from "
             "`eventlfm score` definitions (SPEC 7, eps 4 um, kz 4). Pareto: not beaten in both "
             "speed and error by another point of the same scene (F1 / alpha).\n\n", host);
  for (int s = 0; s < n_sc; s++)
    fprintf(f, "- scene `%s`: %lld events over %.3f s (%.2f Mev/s), seed %lld\n", sc[s].name,
            (long long)sc[s].events, (double)(sc[s].t_last_us - sc[s].t_first_us) * 1e-6,
            sc[s].t_last_us > sc[s].t_first_us
                ? (double)sc[s].events / ((double)(sc[s].t_last_us - sc[s].t_first_us)) : 0.0,
            (long long)op->seed);
  fprintf(f, "\n| scene | axis | setting | status | Mev/s | volumes/s | RTF | RTF (CPU) | peak MB | F1 | "
             "RMSE x | RMSE y | RMSE z | alpha | beta | Pareto | recon / peaks / link / smooth s |\n");
  fprintf(f, "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n");
  for (int i = 0; i < n; i++) {
    const struct point_result *p = &pts[i];
    char c[11][32];
    fmt_num(c[10], 32, "%.3f", p->cpu_s > 0 && !strcmp(p->status, "ok") ? p->span_s / p->cpu_s : NAN);
    fmt_num(c[0], 32, "%.2f", p->events_per_s * 1e-6);
    fmt_num(c[1], 32, "%.0f", p->volumes_per_s);
    fmt_num(c[2], 32, "%.3f", p->rtf);
    fmt_num(c[3], 32, "%.0f", p->peak_rss_mb);
    fmt_num(c[4], 32, "%.3f", p->score.f1);
    fmt_num(c[5], 32, "%.2f", p->score.rmse_x_um);
    fmt_num(c[6], 32, "%.2f", p->score.rmse_y_um);
    fmt_num(c[7], 32, "%.2f", p->score.rmse_z_um);
    fmt_num(c[8], 32, "%.3f", p->score.alpha);
    fmt_num(c[9], 32, "%.3f", p->score.beta);
    char st[96] = "";
    if (isfinite(p->stage_s[0]))
      cli_path_fmt(st, sizeof st, "%.2f / %.2f / %.2f / %.2f", p->stage_s[0], p->stage_s[1],
               p->stage_s[2], p->stage_s[3]);
    fprintf(f, "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s%s | %s |\n",
            p->scene, p->sp->axis, p->sp->setting, p->status, c[0], c[1], c[2], c[10], c[3], c[4],
            c[5], c[6], c[7], c[8], c[9], p->pareto_f1 ? "F1 " : "", p->pareto_alpha ? "alpha" : "", st);
  }
  for (int i = 0; i < n; i++)
    if (pts[i].score.has_stage && pts[i].score.n_frames > 0 && !strcmp(pts[i].status, "ok")) {
      fprintf(f, "\nStage scenes, relative error of the mean track velocity against the truth's "
                 "stage velocity:\n\n| scene | setting | error |\n|---|---|---:|\n");
      for (int j = 0; j < n; j++)
        if (pts[j].score.has_stage && !strcmp(pts[j].status, "ok"))
          fprintf(f, "| %s | %s | %.4f |\n", pts[j].scene, pts[j].sp->setting,
                  pts[j].score.stage_rel_error);
      break;
    }
  if (op->figures)
    fprintf(f, "\nPlots: `bench_error_vs_speed.png` (error against real-time factor, Pareto "
             "fronts as lines), `fig_s4.png` (time surface vs accumulation, MIPs at 1, 5, 10 ms).\n");
  if (n_comps > 0) {
    fprintf(f, "\n## Component benchmarks (same run)\n");
    for (int i = 0; i < n_comps; i++) md_component(f, dir, comps[i]);
  }
  return fclose(f) == 0 ? 0 : -1;
}

/* plot/SCENE.dat: rtf err_f1 err_alpha; plot/SCENE_pf1.dat, _palpha.dat:
 * the fronts sorted by rtf; then plot.gnuplot -> bench_error_vs_speed.png */
static int write_plot(const char *dir, const struct scene_info *sc, int n_sc,
                      const struct point_result *pts, int n, double timeout_s)
{
  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/plot", dir);
  if (cli_mkdir_p(p) != 0) return -1;
  for (int s = 0; s < n_sc; s++) {
    for (int which = 0; which < 3; which++) {
      const char *suffix = which == 0 ? "" : which == 1 ? "_pf1" : "_palpha";
      cli_path_fmt(p, sizeof p, "%s/plot/%s%s.dat", dir, sc[s].name, suffix);
      FILE *f = fopen(p, "w");
      if (!f) return -1;
      fprintf(f, "# rtf err_f1 err_alpha setting (err = 1 - F1, 1 - alpha)\n");
      /* fronts in increasing rtf (selection sort on a few dozen points) */
      int used[BENCH_MAX_POINTS * 4] = {0};
      for (;;) {
        int best = -1;
        for (int i = 0; i < n; i++) {
          const struct point_result *q = &pts[i];
          if (used[i] || strcmp(q->scene, sc[s].name) || strcmp(q->status, "ok")) continue;
          if (which == 1 && !q->pareto_f1) continue;
          if (which == 2 && !q->pareto_alpha) continue;
          if (best < 0 || q->rtf < pts[best].rtf) best = i;
        }
        if (best < 0) break;
        used[best] = 1;
        fprintf(f, "%.6g %.6g %.6g \"%s\"\n", pts[best].rtf, err_f1(&pts[best]),
                err_alpha(&pts[best]), pts[best].sp->setting);
      }
      fclose(f);
    }
  }
  cli_path_fmt(p, sizeof p, "%s/plot.gnuplot", dir);
  FILE *g = fopen(p, "w");
  if (!g) return -1;
  fprintf(g, "# written by eventlfm bench; run from this directory: gnuplot plot.gnuplot\n"
             "set terminal pngcairo size 1400,560 font 'sans,10'\n"
             "set output 'bench_error_vs_speed.png'\n"
             "set multiplot layout 1,2 title 'eventlfm bench: error against speed "
             "(lines: Pareto fronts)'\n"
             "set logscale x\nset grid\nset key top right\n"
             "set xlabel 'real-time factor (recording span / wall time)'\n");
  for (int panel = 0; panel < 2; panel++) {
    fprintf(g, "set ylabel '%s'\nplot ", panel == 0 ? "1 - F1 (detections)" : "1 - alpha (ISBI tracks)");
    for (int s = 0; s < n_sc; s++)
      fprintf(g, "%s'plot/%s.dat' using 1:%d with points pt 7 lc %d title '%s', "
                 "'plot/%s_%s.dat' using 1:%d with linespoints lw 2 lc %d title '%s Pareto front', "
                 "'' using 1:%d:4 with labels font ',8' offset 0.8,0.6 left tc lt %d notitle",
              s ? ", " : "", sc[s].name, panel + 2, s + 1, sc[s].name, sc[s].name,
              panel == 0 ? "pf1" : "palpha", panel + 2, s + 1, sc[s].name, panel + 2, s + 1);
    fprintf(g, "\n");
  }
  fprintf(g, "unset multiplot\n");
  fclose(g);
  char *argv[] = {"gnuplot", "plot.gnuplot", NULL};
  char logp[PATH_MAX], cwd[PATH_MAX];
  cli_path_fmt(logp, sizeof logp, "%s/plot/gnuplot.log", dir);
  if (!getcwd(cwd, sizeof cwd) || chdir(dir) != 0) return -1;
  int rc = cli_run_child(argv, 1, logp, timeout_s, NULL, NULL, NULL);
  if (chdir(cwd) != 0) return -1;
  return rc == 0 ? 0 : -1;
}

/* ---------------------------------------------------------------------- */
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

static int fig_s4(const char *self, const char *dir, const struct scene_info *si,
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

/* ---------------------------------------------------------------------- */

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
          "  --quick         flow only, 50 ms, 23 points (a few minutes on 2 cores)\n"
          "  --out DIR       output directory (default bench_out)\n"
          "  --scenes LIST   built-in scenes (default: flow with --quick, else flow,stage)\n"
          "  --duration-ms D simulated duration per scene (default 50 quick, 300 full)\n"
          "  --timeout-s S   limit per child process (default 300 quick, 1800 full)\n"
          "  --max-points N  only the first N sweep points per scene (smoke tests)\n"
          "  --no-components skip the component benchmarks; --no-figures: no PNGs\n");
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

static int run_components(const char *self, const char *dir, const char *scene_dir, int quick,
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
        if (truth_stage_velocity(tp, si->stage_v_um_per_ms, &err) != ELFM_OK)
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
      char *targv[8 + BENCH_MAX_ARGS + 1];
      int na = 0;
      targv[na++] = self;
      targv[na++] = "track";
      targv[na++] = "--calib";
      targv[na++] = calib;
      targv[na++] = "--events";
      targv[na++] = ev;
      targv[na++] = "--out";
      targv[na++] = run;
      for (int a = 0; sp->args[a]; a++) targv[na++] = (char *)sp->args[a];
      targv[na] = NULL;
      int rc = cli_run_child(targv, 0, logp, op.timeout_s, &p->wall_s, &p->peak_rss_mb, &p->cpu_s);
      if (rc != 0) p->peak_rss_mb = NAN; /* a rejected run's memory means nothing */
      if (rc == 2) p->status = "unsupported";
      else if (rc == -2) p->status = "timeout";
      else if (rc != 0) p->status = "failed";
      else {
        p->status = "ok";
        p->events_per_s = (double)p->events / p->wall_s;
        p->rtf = p->span_s / p->wall_s;
        summary_read(run, &p->volumes, p->stage_s);
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
    mark_pareto(pts, n_pts, si->name, err_f1, 0);
    mark_pareto(pts, n_pts, si->name, err_alpha, 1);
  }

  const char *comp_names[16];
  int n_comps = 0;
  if (op.components)
    run_components(self, dir, sc[0].dir, op.quick, op.quick ? 180 : op.timeout_s, comp_names,
                   &n_comps);

  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/bench.csv", dir);
  if (write_csv(p, pts, n_pts) != 0) { rc_out = cli_message("bench", CLI_FAIL, "cannot write %s", p); goto out; }
  int fig_ok = 1;
  if (op.figures) {
    if (write_plot(dir, sc, n_sc, pts, n_pts, 120) != 0) {
      fprintf(stderr, "eventlfm bench: gnuplot failed; see %s/plot/gnuplot.log\n", dir);
      fig_ok = 0;
    }
    fprintf(stderr, "eventlfm bench: Fig. S4 reconstructions ...\n");
    if (fig_s4(self, dir, &sc[0], op.timeout_s) != 0) fig_ok = 0;
  }
  if (write_md(dir, &op, sc, n_sc, pts, n_pts, comp_names, n_comps, host) != 0)
    { rc_out = cli_message("bench", CLI_FAIL, "cannot write %s/bench.md", dir); goto out; }

  /* Short summary on stdout: the best point per scene. */
  int n_ok = 0;
  for (int i = 0; i < n_pts; i++) n_ok += !strcmp(pts[i].status, "ok");
  printf("eventlfm bench: %d of %d points ran; results in %s/bench.md, bench.csv%s\n", n_ok, n_pts,
         dir, op.figures ? ", bench_error_vs_speed.png, fig_s4.png" : "");
  for (int s = 0; s < n_sc; s++) {
    int fast = -1;
    for (int i = 0; i < n_pts; i++)
      if (!strcmp(pts[i].scene, sc[s].name) && !strcmp(pts[i].status, "ok") &&
          (fast < 0 || pts[i].rtf > pts[fast].rtf))
        fast = i;
    if (fast >= 0)
      printf("  %s: fastest point '%s' RTF %.3f (%.2f Mev/s), F1 %.3f, alpha %.3f\n", sc[s].name,
             pts[fast].sp->setting, pts[fast].rtf, pts[fast].events_per_s * 1e-6,
             pts[fast].score.f1, pts[fast].score.alpha);
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
