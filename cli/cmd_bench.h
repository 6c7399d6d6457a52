/* cmd_bench.h — what the files of `eventlfm bench` share (private to it):
 * the options, a sweep point and its result, a simulated scene; reading
 * back what a point's run wrote (cmd_bench_read.c); the Pareto fronts,
 * bench.csv, bench.md and the error-vs-speed plot (cmd_bench_report.c); the
 * runs beside the sweep, Fig. S4 and the component benchmarks
 * (cmd_bench_extra.c). cmd_bench.c parses the options and runs the sweep. */
#ifndef ELFM_CMD_BENCH_H
#define ELFM_CMD_BENCH_H

#include <limits.h>
#include <stdint.h>
#include <stdio.h>

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

struct scene_info {
  char name[64];
  char dir[PATH_MAX];
  int64_t events, t_first_us, t_last_us;
  int is_stage;              /* a stage scene: score the mean velocity too */
  double stage_v_um_per_ms[3];
};

/* Numbers from the tracker's summary.json in run_dir: the volume count and
 * the per-stage seconds (recon, peaks, link, smooth); -1 / NaN when absent. */
void bench_summary_read(const char *run_dir, double *volumes, double stage_s[4]);
/* The mean velocity of a stage scene's objects from its truth.csv. */
elfm_status bench_truth_stage_velocity(const char *truth_csv, double v[3], elfm_error *err);

/* Mark the points of `scene` on the F1 and on the alpha Pareto front
 * (pareto_f1, pareto_alpha), among that scene's points that ran. */
void bench_mark_pareto(struct point_result *pts, int n, const char *scene);
/* bench.csv at path, bench.md in dir (comps: the component benchmarks whose
 * logs it quotes), plot/ and bench_error_vs_speed.png in dir (gnuplot);
 * 0, or -1 when a file could not be written or gnuplot failed. */
int bench_write_csv(const char *path, const struct point_result *pts, int n);
int bench_write_md(const char *dir, const struct bench_opts *op, const struct scene_info *sc,
                   int n_sc, const struct point_result *pts, int n, const char *const *comps,
                   int n_comps, const char *host);
int bench_write_plot(const char *dir, const struct scene_info *sc, int n_sc,
                     const struct point_result *pts, int n, double timeout_s);

/* fig_s4.png in dir from `self recon` runs on the scene si; 0, or -1 (after
 * saying which panel failed, when it was a recon run). */
int bench_fig_s4(const char *self, const char *dir, const struct scene_info *si,
                 double timeout_s);
/* Run the component benchmarks built beside self (bench/bench_*), logs in
 * dir/components/; names[*n_out] the ones with a log. 0, or -1 when that
 * directory cannot be made. */
int bench_run_components(const char *self, const char *dir, const char *scene_dir, int quick,
                         double timeout_s, const char **names, int *n_out);

#endif
