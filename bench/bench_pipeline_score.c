/* bench_pipeline_score.c — speed of the pipeline's last stage: the
 * Hungarian solver (also used by the linker) and SPEC §7 scoring.
 *
 *   build-NAME/bench/bench_pipeline_score [--quick]
 *
 * 1. elfm_assign_hungarian on n x n problems, n = 10, 100, 300, 1000 (--quick
 *    stops at 300): dense uniform costs (the O(n^3) worst case) and gated
 *    costs (each row allows ~5 columns, the linker's typical case).
 * 2. elfm_score_tables on synthetic scenes of N objects x F frames with
 *    noisy perfect tracks, timed without CSV parsing (tables are parsed from
 *    memory first), so the figure is the scorer's own cost.
 * Times are the best of 3 runs (monotonic clock).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "elfm_tracker.h"
#include "bench_clock.h"

static double rnd(uint64_t *s)
{
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return (double)((*s * 2685821657736338717ULL) >> 11) / 9007199254740992.0;
}

static double gauss(uint64_t *s)
{
  double u = rnd(s) + 1e-300, v = rnd(s);
  return sqrt(-2.0 * log(u)) * cos(6.283185307179586 * v);
}

typedef struct { char *s; size_t n, cap; } buf_t;
static void put(buf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(buf_t *b, const char *fmt, ...)
{
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->s + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    if (k >= 0 && (size_t)k < b->cap - b->n) { b->n += (size_t)k; return; }
    b->cap = b->cap * 2 + (size_t)k + 64;
    b->s = realloc(b->s, b->cap);
    if (!b->s) { fprintf(stderr, "out of memory\n"); exit(1); }
  }
}

static int bench_hungarian(int quick)
{
  static const int sizes[] = {10, 100, 300, 1000};
  uint64_t seed = 12345;
  elfm_error err;
  elfm_assign_workspace *ws = NULL;
  if (elfm_assign_workspace_create(0, 0, &ws, &err) != ELFM_OK) return 1;
  printf("Hungarian (elfm_assign_hungarian), best of 3\n");
  printf("  %6s %14s %14s\n", "n", "dense ms", "gated ms");
  for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
    int n = sizes[k];
    if (quick && n > 300) break;
    double *c = malloc((size_t)n * (size_t)n * sizeof *c);
    double *g = malloc((size_t)n * (size_t)n * sizeof *g);
    int *r2c = malloc((size_t)n * sizeof *r2c);
    if (!c || !g || !r2c) return 1;
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) {
        c[(size_t)i * n + j] = rnd(&seed);
        /* gated: about 5 allowed columns per row around the diagonal */
        int dj = abs(i - j);
        g[(size_t)i * n + j] = dj <= 2 ? rnd(&seed) * 4.0 : INFINITY;
      }
    double best[2] = {1e30, 1e30};
    for (int rep = 0; rep < 3; rep++)
      for (int which = 0; which < 2; which++) {
        double t0 = bench_wall_s();
        if (elfm_assign_hungarian(which ? g : c, n, n, r2c, NULL, ws, &err) != ELFM_OK) return 1;
        double dt = bench_wall_s() - t0;
        if (dt < best[which]) best[which] = dt;
      }
    printf("  %6d %14.3f %14.3f\n", n, best[0] * 1e3, best[1] * 1e3);
    free(c);
    free(g);
    free(r2c);
  }
  elfm_assign_workspace_free(ws);
  return 0;
}

static int bench_score(int n_obj, int n_frames)
{
  uint64_t seed = 99;
  buf_t tb = {malloc(1 << 20), 0, 1 << 20}, kb = {malloc(1 << 20), 0, 1 << 20};
  if (!tb.s || !kb.s) return 1;
  double *x0 = malloc((size_t)n_obj * 5 * sizeof *x0);
  if (!x0) return 1;
  for (int k = 0; k < n_obj; k++) {
    x0[5 * k + 0] = rnd(&seed) * 120 - 60;
    x0[5 * k + 1] = rnd(&seed) * 120 - 60;
    x0[5 * k + 2] = rnd(&seed) * 180 - 90;
    x0[5 * k + 3] = rnd(&seed) * 0.1 - 0.05; /* um/ms */
    x0[5 * k + 4] = rnd(&seed) * 0.1 - 0.05;
  }
  put(&tb, "id,t_us,x_um,y_um,z_um,brightness\n");
  int64_t span_us = 1000LL * (n_frames + 1);
  for (int64_t t = 0; t <= span_us; t += 100)
    for (int k = 0; k < n_obj; k++)
      put(&tb, "%d,%lld,%.4f,%.4f,%.3f,1\n", k, (long long)t, x0[5 * k] + x0[5 * k + 3] * t * 1e-3,
          x0[5 * k + 1] + x0[5 * k + 4] * t * 1e-3, x0[5 * k + 2]);
  put(&kb, "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um\n");
  for (int k = 0; k < n_obj; k++)
    for (int f = 0; f < n_frames; f++) {
      int64_t t = 1000LL * (f + 1);
      double x = x0[5 * k] + x0[5 * k + 3] * t * 1e-3 + 0.3 * gauss(&seed);
      double y = x0[5 * k + 1] + x0[5 * k + 4] * t * 1e-3 + 0.3 * gauss(&seed);
      double z = x0[5 * k + 2] + 1.0 * gauss(&seed);
      put(&kb, "%d,%d,%lld,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", k, f, (long long)t, x, y, z, x, y, z);
    }
  elfm_error err;
  elfm_table *truth = NULL, *tracks = NULL;
  double tp0 = bench_wall_s();
  if (elfm_table_parse(tb.s, tb.n, "truth.csv", &truth, &err) != ELFM_OK ||
      elfm_table_parse(kb.s, kb.n, "tracks.csv", &tracks, &err) != ELFM_OK) {
    fprintf(stderr, "parse: %s\n", err.message);
    return 1;
  }
  double parse_s = bench_wall_s() - tp0;
  elfm_score_options o;
  elfm_score_options_default(&o);
  elfm_score_result r;
  double best = 1e30;
  for (int rep = 0; rep < 3; rep++) {
    double t0 = bench_wall_s();
    if (elfm_score_tables(truth, tracks, NULL, &o, &r, &err) != ELFM_OK) {
      fprintf(stderr, "score: %s\n", err.message);
      return 1;
    }
    double dt = bench_wall_s() - t0;
    if (dt < best) best = dt;
  }
  printf("  %6d objects x %5d frames: score %8.1f ms (%.2f M track points/s), CSV parse %8.1f "
         "ms; F1 %.4f alpha %.4f\n",
         n_obj, n_frames, best * 1e3, (double)n_obj * n_frames / best * 1e-6, parse_s * 1e3, r.f1,
         r.alpha);
  elfm_table_free(truth);
  elfm_table_free(tracks);
  free(tb.s);
  free(kb.s);
  free(x0);
  return 0;
}

int main(int argc, char **argv)
{
  int quick = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--quick")) quick = 1;
    else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      printf("usage: bench_pipeline_score [--quick]\n"
             "Times the Hungarian solver (n = 10..1000) and SPEC 7 scoring on synthetic scenes.\n");
      return 0;
    } else {
      fprintf(stderr, "bench_pipeline_score: unknown argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (bench_hungarian(quick)) return 1;
  printf("Scoring (elfm_score_tables, tracks only, detections from raw points), best of 3\n");
  if (bench_score(100, 200)) return 1;
  if (bench_score(100, 1000)) return 1;
  if (!quick && bench_score(1000, 500)) return 1;
  return 0;
}
