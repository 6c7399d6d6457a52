/* bench_smooth.c — Ceres smoothing time per 1,000-point track, per model
 * and linear solver (a wiggling 3D path, 0.1 / 0.4 um noise, 1 kHz).
 *   build-NAME/bench/bench_smooth [repeats]     (default 5) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "elfm_tracker.h"
#include "bench_clock.h"

int main(int argc, char **argv)
{
  int reps = argc > 1 ? atoi(argv[1]) : 5;
  if (reps < 1) reps = 1;
  enum { N = 1000 };
  static int64_t t[N];
  static double x[3 * N], p[3 * N], v[3 * N], ps[3 * N], vs[3 * N];
  uint64_t s = 99;
  for (int i = 0; i < N; i++) {
    t[i] = 5000000000000LL + 1000LL * i;
    double g[3];
    for (int a = 0; a < 3; a++) {
      s ^= s << 13; s ^= s >> 7; s ^= s << 17;
      double u1 = (double)(s >> 11) / 9007199254740992.0 + 1e-12;
      s ^= s << 13; s ^= s >> 7; s ^= s << 17;
      double u2 = (double)(s >> 11) / 9007199254740992.0;
      g[a] = sqrt(-2 * log(u1)) * cos(6.283185307179586 * u2);
    }
    x[3 * i] = 4 * sin(i / 60.0 * 6.283) + 0.1 * g[0];
    x[3 * i + 1] = 0.05 * i + 0.1 * g[1];
    x[3 * i + 2] = 8 * cos(i / 60.0 * 6.283) + 0.4 * g[2];
  }
  struct { const char *name; elfm_motion_model m; elfm_smooth_solver so; } cases[] = {
      {"auto (CV + CA + spline, chosen)", ELFM_MODEL_AUTO, ELFM_SOLVER_AUTO},
      {"constant velocity", ELFM_MODEL_CONST_VELOCITY, ELFM_SOLVER_AUTO},
      {"constant acceleration", ELFM_MODEL_CONST_ACCEL, ELFM_SOLVER_AUTO},
      {"spline, GCV weight, sparse", ELFM_MODEL_SPLINE, ELFM_SOLVER_SPARSE},
  };
  printf("model                              ms_per_1000_point_track  chosen\n");
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    elfm_smooth_options o;
    elfm_smooth_options_default(&o);
    o.model = cases[c].m;
    o.solver = cases[c].so;
    elfm_smooth_info info;
    elfm_error err;
    int r = reps;  /* (dense QR on the spline's 3,000 unknowns took 169 s: not benchmarked) */
    double t0 = bench_wall_s();
    for (int k = 0; k < r; k++)
      if (elfm_smooth_fit(&o, N, t, x, NULL, N, t, p, v, ps, vs, &info, &err) != ELFM_OK) {
        fprintf(stderr, "smooth failed: %s\n", err.message);
        return 1;
      }
    double ms = 1e3 * (bench_wall_s() - t0) / r;
    printf("%-35s  %23.2f  %s\n", cases[c].name, ms, elfm_motion_model_name(info.model));
    fflush(stdout);
  }
  return 0;
}
