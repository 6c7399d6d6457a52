/* bench_simulate.c — speed of the simulator: one second of the `flow` scene
 * with 100 beads by default, written to a temporary directory (events.raw,
 * truth.csv, calib.json) exactly as `eventlfm simulate` does.
 *
 *   build-NAME/bench/bench_simulate [SCENE] [OBJECTS] [DURATION_MS] [SEED]
 *
 * Prints the wall and CPU time (this process, one thread), the events
 * produced per simulated second and per second of CPU time, the number of
 * pixel-model updates and the peak memory. The target of issue 3 is one
 * simulated second of flow with 100 beads in <= 30 s on one core. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "elfm_datasets.h"
#include "bench_clock.h"

static void rm_out(const char *dir)
{
  const char *files[] = {"events.raw", "truth.csv", "calib.json", "stimulus.csv"};
  char p[600];
  for (int i = 0; i < 4; i++) {
    snprintf(p, sizeof p, "%s/%s", dir, files[i]);
    unlink(p);
  }
  rmdir(dir);
}

int main(int argc, char **argv)
{
  const char *scene = argc > 1 ? argv[1] : "flow";
  int n_obj = argc > 2 ? atoi(argv[2]) : 100;
  double dur_ms = argc > 3 ? atof(argv[3]) : 1000.0;
  long seed = argc > 4 ? atol(argv[4]) : 1;
  if (argc > 5 || n_obj < 0 || !(dur_ms > 0) || seed < 0) {
    fprintf(stderr, "usage: bench_simulate [SCENE] [OBJECTS] [DURATION_MS] [SEED]\n");
    return 2;
  }
  elfm_error err;
  elfm_error_clear(&err);
  elfm_scene *s = NULL;
  char kv[64], buf[1200];
  if (elfm_scene_load(scene, &s, &err)) goto fail;
  snprintf(kv, sizeof kv, "objects.count=%d", n_obj);
  if (elfm_scene_set_param(s, kv, &err)) goto fail;
  snprintf(kv, sizeof kv, "duration_ms=%.17g", dur_ms);
  if (elfm_scene_set_param(s, kv, &err)) goto fail;
  if (elfm_scene_set_seed(s, (uint64_t)seed, &err)) goto fail;

  char dir[] = "/tmp/bench_simulate_XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    elfm_scene_free(s);
    return 1;
  }
  elfm_sim_stats st;
  double c0 = bench_cpu_s(), w0 = bench_wall_s();
  elfm_status rc = elfm_sim_run(s, dir, NULL, &st, &err);
  double cpu = bench_cpu_s() - c0, wall = bench_wall_s() - w0;
  rm_out(dir);
  if (rc) goto fail;
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  printf("bench_simulate: scene %s, %d objects, %.0f ms simulated, seed %ld\n", scene, n_obj,
         dur_ms, seed);
  printf("  wall %.2f s, cpu %.2f s (one thread)  -> %.1f s of cpu per simulated second\n", wall,
         cpu, cpu / (dur_ms * 1e-3));
  printf("  events %lld (%.2f Mev per simulated s; %lld from light changes, %lld noise)\n",
         (long long)st.n_events, st.events_per_s * 1e-6, (long long)st.n_signal,
         (long long)st.n_noise);
  printf("  produced %.2f Mev per cpu second\n", (double)st.n_events / cpu * 1e-6);
  printf("  %lld time steps, %.3g pixel updates (%.1f ns of cpu each, all costs included)\n",
         (long long)st.n_steps, (double)st.n_pixel_steps,
         st.n_pixel_steps ? cpu / (double)st.n_pixel_steps * 1e9 : 0.0);
  printf("  peak RSS %.1f MB\n", (double)ru.ru_maxrss / 1024.0);
  elfm_scene_free(s);
  return 0;
fail:
  fprintf(stderr, "bench_simulate: %s\n", elfm_error_format(&err, buf, sizeof buf));
  elfm_scene_free(s);
  return 1;
}
