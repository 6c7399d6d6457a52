/* bench_clock.h — the benchmark programs' two clocks. Every figure is
 * reported as wall time and as CPU time: on a shared machine the wall clock
 * also counts other people's work. */
#ifndef ELFM_BENCH_CLOCK_H
#define ELFM_BENCH_CLOCK_H

#include <time.h>

/* Monotonic wall clock, seconds. */
static inline double bench_wall_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* CPU time of the whole process (all threads, user + system), seconds. */
static inline double bench_cpu_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
