/* bench_link.c — linking speed: FLANN k-d tree candidates vs brute force,
 * at 100, 1,000 and 10,000 objects per frame (objects drifting with their
 * own velocities in a 400 x 400 x 200 um box, 0.1 um noise, 1 kHz).
 * Prints ms per frame for each and checks both give the same tracks.
 *   build-NAME/bench/bench_link [frames]     (default 20) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "elfm_tracker.h"
#include "bench_clock.h"

static uint64_t rng = 12345;
static double urand(void)
{
  rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
  return (double)(rng >> 11) / 9007199254740992.0;
}

/* Returns ms per frame; *n_tracks the finished tracks. */
static double run(int n, int frames, int brute, const double *p0, const double *v, size_t *n_tracks)
{
  elfm_error err;
  elfm_link_options o;
  elfm_link_options_default(&o);
  o.brute_force = brute;
  o.trail_us = 0;
  elfm_linker *l = elfm_link_create(&o, &err);
  elfm_detection *d = calloc((size_t)n, sizeof *d);
  uint64_t seed = rng;
  double t = 0;
  for (int f = 0; f < frames; f++) {
    for (int i = 0; i < n; i++) {
      d[i].x_um = p0[3 * i] + v[3 * i] * f + 0.1 * (urand() - 0.5);
      d[i].y_um = p0[3 * i + 1] + v[3 * i + 1] * f + 0.1 * (urand() - 0.5);
      d[i].z_um = p0[3 * i + 2] + v[3 * i + 2] * f + 0.4 * (urand() - 0.5);
    }
    double t0 = bench_wall_s();
    if (elfm_link_step(l, f, 1000000000000LL + 1000LL * f, d, n, &err) != ELFM_OK) {
      fprintf(stderr, "link failed: %s\n", err.message);
      exit(1);
    }
    t += bench_wall_s() - t0;
  }
  elfm_link_finish(l, &err);
  size_t k = 0;
  elfm_track *tr;
  while ((tr = elfm_link_pop_finished(l))) {
    k++;
    elfm_track_free(tr);
  }
  *n_tracks = k;
  elfm_link_free(l);
  free(d);
  rng = seed;
  return 1e3 * t / frames;
}

int main(int argc, char **argv)
{
  int frames = argc > 1 ? atoi(argv[1]) : 20;
  if (frames < 2) frames = 2;
  printf("objects  kdtree_ms_per_frame  brute_ms_per_frame  speedup  tracks_kdtree  tracks_brute\n");
  const int sizes[3] = {100, 1000, 10000};
  for (int s = 0; s < 3; s++) {
    int n = sizes[s];
    double *p0 = malloc(sizeof(double) * 3 * n), *v = malloc(sizeof(double) * 3 * n);
    /* a grid with jitter: >= 5 um apart, so the answer is unambiguous */
    int side = 1;
    while (side * side * side < n) side++;
    double sp = 5.0 + 400.0 / side;
    for (int i = 0; i < n; i++) {
      p0[3 * i] = (i % side) * sp + urand();
      p0[3 * i + 1] = ((i / side) % side) * sp + urand();
      p0[3 * i + 2] = (i / (side * side)) * sp * 2 + urand();
      for (int a = 0; a < 3; a++) v[3 * i + a] = 0.6 * urand() - 0.3;
    }
    size_t tk, tb;
    uint64_t seed = rng;
    double mk = run(n, frames, 0, p0, v, &tk);
    rng = seed;
    double mb = run(n, frames, 1, p0, v, &tb);
    printf("%7d  %19.3f  %18.3f  %7.1f  %13zu  %12zu\n", n, mk, mb, mb / mk, tk, tb);
    fflush(stdout);
    free(p0);
    free(v);
  }
  return 0;
}
