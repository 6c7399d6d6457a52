/* cmd_bench_report.c — what `eventlfm bench` writes of the sweep: the
 * Pareto fronts, bench.csv, bench.md and the error-vs-speed plot
 * (cmd_bench.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cmd_bench.h"

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

void bench_mark_pareto(struct point_result *pts, int n, const char *scene)
{
  mark_pareto(pts, n, scene, err_f1, 0);
  mark_pareto(pts, n, scene, err_alpha, 1);
}

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

int bench_write_csv(const char *path, const struct point_result *pts, int n)
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

int bench_write_md(const char *dir, const struct bench_opts *op, const struct scene_info *sc,
                   int n_sc, const struct point_result *pts, int n, const char *const *comps,
                   int n_comps, const char *host)
{
  char path[PATH_MAX];
  cli_path_fmt(path, sizeof path, "%s/bench.md", dir);
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fprintf(f, "# eventlfm bench%s\n\n", op->quick ? " --quick" : "");
  fprintf(f, "Machine: %s. Every point runs `eventlfm track` as a child process; wall time "
             "includes process start, reading the events and writing all outputs (each scene's "
             "first point ran once before, untimed, into runs/SCENE_warmup, so that it does not "
             "pay alone for a cold page cache). Real-time "
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
int bench_write_plot(const char *dir, const struct scene_info *sc, int n_sc,
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
