/* bench_refocus.c — refocusing speed at the paper's geometry (144 x 144 px
 * views, 101 planes, 25 views): volumes per second of the dense and the
 * event-sparse path on 1 and 2 threads, on frames of a simulated scene
 * (default: flow, 20 beads, ~13 Mev/s) or of a recording.
 *
 *   bench_refocus [--scene NAME] [--objects N] [--ms N] [--events E --calib C]
 *                 [--median 0|3|5] [--dt-us N] [--reps N] [--agree F (0 = off)]
 *                 [--path dense|sparse|both]
 *
 * Steps, each timed on its own: events -> frames (framer), median, refocus.
 * Frames are built once and kept (sparse, in memory); refocusing then runs
 * over them `reps` times per configuration, parallel across frames with a
 * workspace and a volume per thread, as elfm_recon_run does.
 */
#include <getopt.h>
#include <limits.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "elfm_datasets.h"
#include "elfm_recon.h"
#include "bench_clock.h"

typedef struct kept {          /* a frame kept as its listed pixels */
  uint32_t *idx;
  float *val;
  size_t nnz;
  int64_t t_us, index;
} kept;

typedef struct bench {
  elfm_framer *framer;
  elfm_median *median;
  elfm_frame *raw, *filt;
  kept *frames;
  size_t n_frames, cap_frames, max_frames;
  double t_framer, t_median;
  int64_t events;
  double nnz_raw, nnz_med;
} bench;

static int keep_frame(bench *b, const elfm_frame *f)
{
  if (b->n_frames == b->cap_frames) {
    size_t c = b->cap_frames ? 2 * b->cap_frames : 256;
    kept *k = realloc(b->frames, c * sizeof *k);
    if (!k) return 0;
    b->frames = k;
    b->cap_frames = c;
  }
  kept *k = &b->frames[b->n_frames++];
  k->nnz = f->nnz;
  k->idx = malloc((f->nnz + 1) * sizeof *k->idx);
  k->val = malloc((f->nnz + 1) * sizeof *k->val);
  if (!k->idx || !k->val) return 0;
  for (size_t i = 0; i < f->nnz; i++) {
    k->idx[i] = f->idx[i];
    k->val[i] = f->data[f->idx[i]];
  }
  k->t_us = f->t_us;
  k->index = f->index;
  return 1;
}

static void drain(bench *b)
{
  for (;;) {
    if (b->n_frames >= b->max_frames) return;
    double t0 = bench_wall_s();
    int got = elfm_framer_next(b->framer, b->raw);
    b->t_framer += bench_wall_s() - t0;
    if (!got) return;
    const elfm_frame *f = b->raw;
    b->nnz_raw += (double)b->raw->nnz;
    if (b->median) {
      t0 = bench_wall_s();
      elfm_median_apply(b->median, b->raw, b->filt);
      b->t_median += bench_wall_s() - t0;
      f = b->filt;
    }
    b->nnz_med += (double)f->nnz;
    if (!keep_frame(b, f)) return;
  }
}

static elfm_status sink(void *user, const elfm_event_chunk *c, elfm_error *err)
{
  bench *b = user;
  double t0 = bench_wall_s();
  elfm_status st = elfm_framer_push(b->framer, c, err);
  b->t_framer += bench_wall_s() - t0;
  b->events += (int64_t)c->n;
  drain(b);
  return st;
}

static void unpack(const kept *k, elfm_frame *f)
{
  elfm_frame_clear(f);
  for (size_t i = 0; i < k->nnz; i++) {
    f->idx[i] = k->idx[i];
    f->data[k->idx[i]] = k->val[i];
  }
  f->nnz = k->nnz;
  f->t_us = k->t_us;
  f->index = k->index;
}

/* Refocus every kept frame `reps` times on `threads` threads: volumes/s. */
static double run_refocus(const elfm_refocus_plan *plan, elfm_refocus_path path, const bench *b,
                          int threads, int reps, const elfm_calib *c, double *cpu_per_volume)
{
  int ok = 1;
  double t0 = 0, t1 = 0, c0 = 0, c1 = 0;
#pragma omp parallel num_threads(threads)
  {
    elfm_error err;
    elfm_refocus_workspace *ws = NULL;
    elfm_volume *vol = elfm_refocus_volume_create(plan, &err);
    elfm_frame *f = elfm_frame_create(c->sensor_width_px, c->sensor_height_px, &err);
    if (elfm_refocus_workspace_create(plan, &ws, &err) || !vol || !f) {
#pragma omp atomic write
      ok = 0;
    }
    /* one untimed pass: first-touch of the volume pages */
    if (ws && vol && f) {
      unpack(&b->frames[0], f);
      elfm_refocus_execute_path(plan, path, f, vol, ws, &err);
    }
#pragma omp barrier
#pragma omp single
    {
      t0 = bench_wall_s();
      c0 = bench_cpu_s();
    }
    if (ws && vol && f)
      for (int r = 0; r < reps; r++) {
#pragma omp for schedule(dynamic, 1) nowait
        for (size_t i = 0; i < b->n_frames; i++) {
          unpack(&b->frames[i], f);
          if (elfm_refocus_execute_path(plan, path, f, vol, ws, &err)) {
#pragma omp atomic write
            ok = 0;
          }
        }
      }
#pragma omp barrier
#pragma omp single
    {
      t1 = bench_wall_s();
      c1 = bench_cpu_s();
    }
    elfm_frame_free(f);
    elfm_volume_free(vol);
    elfm_refocus_workspace_free(ws);
  }
  if (!ok) return -1;
  *cpu_per_volume = (c1 - c0) / ((double)b->n_frames * reps);
  return (double)b->n_frames * reps / (t1 - t0);
}

int main(int argc, char **argv)
{
  const char *scene = "flow", *events = NULL, *calib_path = NULL;
  int objects = 0, ms = 100, median = 3, reps = 3;
  double agree = -1; /* < 0: the library default */
  int only = -1;     /* --path: 0 dense, 1 sparse, -1 both */
  int64_t dt_us = 1000;
  static const struct option opts[] = {
    {"scene", required_argument, 0, 's'}, {"objects", required_argument, 0, 'o'},
    {"ms", required_argument, 0, 'm'}, {"events", required_argument, 0, 'e'},
    {"calib", required_argument, 0, 'c'}, {"median", required_argument, 0, 'M'},
    {"dt-us", required_argument, 0, 'd'}, {"reps", required_argument, 0, 'r'},
    {"agree", required_argument, 0, 'a'}, {"path", required_argument, 0, 'p'},
    {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
  int ch;
  while ((ch = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
    switch (ch) {
    case 's': scene = optarg; break;
    case 'o': objects = atoi(optarg); break;
    case 'm': ms = atoi(optarg); break;
    case 'e': events = optarg; break;
    case 'c': calib_path = optarg; break;
    case 'M': median = atoi(optarg); break;
    case 'd': dt_us = atoll(optarg); break;
    case 'r': reps = atoi(optarg); break;
    case 'a': agree = atof(optarg); break;
    case 'p': only = !strcmp(optarg, "dense") ? 0 : !strcmp(optarg, "sparse") ? 1 : -1; break;
    case 'h':
      printf("usage: bench_refocus [--scene NAME] [--objects N] [--ms N] [--events E --calib C]\n"
             "                     [--median 0|3|5] [--dt-us N] [--reps N] [--agree F]\n"
             "                     [--path dense|sparse|both]\n");
      return 0;
    default: return 2;
    }
  }
  if (ms <= 0 || reps <= 0 || (events && !calib_path)) {
    fprintf(stderr, "bench_refocus: bad arguments (--events needs --calib)\n");
    return 2;
  }
  elfm_error err;
  elfm_calib cal;
  elfm_scene *sc = NULL;
  if (events) {
    if (elfm_calib_load(calib_path, &cal, &err)) {
      fprintf(stderr, "bench_refocus: %s\n", err.message);
      return 1;
    }
  } else {
    char kv[64];
    if (elfm_scene_load(scene, &sc, &err)) {
      fprintf(stderr, "bench_refocus: %s\n", err.message);
      return 1;
    }
    snprintf(kv, sizeof kv, "duration_ms=%d", ms);
    if (elfm_scene_set_param(sc, kv, &err)) return 1;
    if (objects > 0) {
      snprintf(kv, sizeof kv, "objects.count=%d", objects);
      if (elfm_scene_set_param(sc, kv, &err)) {
        fprintf(stderr, "bench_refocus: %s\n", err.message);
        return 1;
      }
    }
    cal = *elfm_scene_calib(sc);
  }
  bench b;
  memset(&b, 0, sizeof b);
  b.max_frames = (size_t)ms * 1000 / (size_t)dt_us + 1;
  elfm_framer_options fo;
  elfm_framer_options_default(&fo);
  fo.dt_us = dt_us;
  fo.tau_us = (double)dt_us;
  if (elfm_framer_create(&fo, cal.sensor_width_px, cal.sensor_height_px, &b.framer, &err)) return 1;
  b.raw = elfm_frame_create(cal.sensor_width_px, cal.sensor_height_px, &err);
  b.filt = elfm_frame_create(cal.sensor_width_px, cal.sensor_height_px, &err);
  if (median && elfm_median_create(median, cal.sensor_width_px, cal.sensor_height_px, &b.median, &err))
    return 1;
  double t0 = bench_wall_s();
  double load[1] = {0};
  FILE *la = fopen("/proc/loadavg", "r");
  if (la) {
    if (fscanf(la, "%lf", &load[0]) != 1) load[0] = 0;
    fclose(la);
  }
  if (events) {
    elfm_reader *r = NULL;
    elfm_event_chunk *c = elfm_chunk_create(65536, &err);
    if (elfm_reader_open(events, NULL, &r, &err)) {
      fprintf(stderr, "bench_refocus: %s: %s\n", err.file, err.message);
      return 1;
    }
    while (b.n_frames < b.max_frames && !elfm_reader_read(r, c, &err) && (c->n || c->n_trig))
      sink(&b, c, &err);
    elfm_reader_close(r);
    elfm_chunk_free(c);
  } else {
    elfm_sim_stats ss;
    if (elfm_sim_run_sink(sc, sink, &b, NULL, &ss, &err)) {
      fprintf(stderr, "bench_refocus: simulate: %s\n", err.message);
      return 1;
    }
  }
  elfm_framer_finish(b.framer);
  drain(&b);
  double t_make = bench_wall_s() - t0;
  if (b.n_frames < 2) {
    fprintf(stderr, "bench_refocus: only %zu frames\n", b.n_frames);
    return 1;
  }
  double span_s = (double)b.n_frames * (double)dt_us * 1e-6;
  printf("bench_refocus: %s, %d x %d px views, %d planes, %d views, dt %lld us, median %d "
         "(load average %.1f on %d cores)\n",
         events ? events : scene, cal.view_w_px, cal.view_h_px, elfm_calib_n_planes(&cal),
         cal.n_views, (long long)dt_us, median, load[0], omp_get_num_procs());
  printf("input: %lld events in %zu frames (%.1f Mev/s of recording), made in %.2f s\n",
         (long long)b.events, b.n_frames, (double)b.events / span_s * 1e-6, t_make);
  printf("per frame: %.0f events, %.0f pixels listed, %.0f after median\n",
         (double)b.events / (double)b.n_frames, b.nnz_raw / (double)b.n_frames,
         b.nnz_med / (double)b.n_frames);
  printf("framer: %.1f us/frame (%.1f Mev/s), median: %.1f us/frame (1 thread)\n",
         1e6 * b.t_framer / (double)b.n_frames, (double)b.events / b.t_framer * 1e-6,
         1e6 * b.t_median / (double)b.n_frames);
  elfm_refocus_plan *plan = NULL;
  t0 = bench_wall_s();
  elfm_refocus_options ro;
  elfm_refocus_options_default(&ro);
  if (agree >= 0) ro.agree_frac = agree;
  printf("ghost rule: view agreement %.2f\n", ro.agree_frac);
  if (elfm_refocus_plan_create(&cal, &ro, &plan, &err)) {
    fprintf(stderr, "bench_refocus: %s\n", err.message);
    return 1;
  }
  printf("plan: %.1f ms\n", 1e3 * (bench_wall_s() - t0));
  {
    /* how sparse the output is: voxels the sparse path writes in one volume */
    elfm_refocus_workspace *ws = NULL;
    elfm_volume *vol = elfm_refocus_volume_create(plan, &err);
    elfm_frame *f = elfm_frame_create(cal.sensor_width_px, cal.sensor_height_px, &err);
    if (vol && f && !elfm_refocus_workspace_create(plan, &ws, &err)) {
      double sum = 0;
      size_t nvox = (size_t)vol->w * vol->h * vol->nz;
      for (size_t i = b.n_frames / 2; i < b.n_frames / 2 + 10 && i < b.n_frames; i++) {
        unpack(&b.frames[i], f);
        elfm_refocus_execute_path(plan, ELFM_PATH_SPARSE, f, vol, ws, &err);
        size_t nz = 0;
        for (size_t j = 0; j < nvox; j++) nz += vol->data[j] != 0.0f;
        sum += (double)nz / (double)nvox;
      }
      printf("output: %.0f%% of the voxels non-zero (mean of 10 volumes)\n", 100.0 * sum / 10.0);
    }
    elfm_refocus_workspace_free(ws);
    elfm_volume_free(vol);
    elfm_frame_free(f);
  }
  double vps[2][2] = {{0, 0}, {0, 0}};
  for (int path = 0; path < 2; path++)
    for (int th = 1; th <= 2; th++) {
      if (only >= 0 && path != only) continue;
      int r = path == 0 ? 1 : reps; /* dense is slow: one pass is plenty of frames */
      double cpu = 0;
      vps[path][th - 1] = run_refocus(plan, path ? ELFM_PATH_SPARSE : ELFM_PATH_DENSE, &b, th, r, &cal, &cpu);
      printf("refocus %-6s %d thread%s: %8.1f volumes/s wall (%.3f ms/volume); CPU %.3f ms/volume "
             "(%.0f volumes/s per busy core)\n", path ? "sparse" : "dense", th, th > 1 ? "s" : " ",
             vps[path][th - 1], 1e3 / vps[path][th - 1], 1e3 * cpu, 1.0 / cpu);
    }
  if (only < 0)
    printf("sparse/dense: %.1fx (1 thread), %.1fx (2 threads)\n", vps[1][0] / vps[0][0],
           vps[1][1] / vps[0][1]);
  for (size_t i = 0; i < b.n_frames; i++) {
    free(b.frames[i].idx);
    free(b.frames[i].val);
  }
  free(b.frames);
  elfm_refocus_plan_free(plan);
  elfm_framer_free(b.framer);
  elfm_median_free(b.median);
  elfm_frame_free(b.raw);
  elfm_frame_free(b.filt);
  elfm_scene_free(sc);
  return 0;
}
