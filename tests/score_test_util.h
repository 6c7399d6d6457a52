/* score_test_util.h — what the scorer's tests share (include after check.h
 * and elfm_tracker.h): the two-object scene of test_score.c (see there),
 * a growing text buffer and a parser for the tables written into it. */
#ifndef ELFM_TESTS_SCORE_TEST_UTIL_H
#define ELFM_TESTS_SCORE_TEST_UTIL_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NF 20
static inline double frame_t(int f) { return 1000.0 + 1000.0 * f; }

static inline void pos(int obj, double t, double *x, double *y, double *z)
{
  if (obj == 0) { *x = -10 + 0.001 * t; *y = -20; *z = 5; }
  else { *x = 10 - 0.001 * t; *y = 20; *z = -10 + 0.0004 * t; }
}

/* A growing text buffer. */
typedef struct { char *s; size_t n, cap; } buf_t;
static inline void bprintf(buf_t *b, const char *fmt, ...)
{
  va_list ap;
  for (;;) {
    va_start(ap, fmt);
    int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
    va_end(ap);
    if (b->s && (size_t)k < b->cap - b->n) { b->n += (size_t)k; return; }
    b->cap = (b->cap + (size_t)k + 1) * 2;
    b->s = realloc(b->s, b->cap);
    if (!b->s) abort();
  }
}

static inline elfm_table *parse(buf_t *b, const char *name)
{
  elfm_table *t = NULL;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_status s = elfm_table_parse(b->s, b->n, name, &t, &err);
  if (s != ELFM_OK) {
    char m[1200];
    fprintf(stderr, "test input did not parse: %s\n", elfm_error_format(&err, m, sizeof m));
    abort();
  }
  free(b->s);
  memset(b, 0, sizeof *b);
  return t;
}

/* truth.csv of the scene, sampled every 100 us over 0-25 ms, with each
 * object's brightness from br(object, t_us, arg). */
static inline elfm_table *make_truth_with(double (*br)(int o, int t_us, double arg), double arg)
{
  buf_t b = {0};
  bprintf(&b, "id,t_us,x_um,y_um,z_um,brightness\n");
  for (int t = 0; t <= 25000; t += 100)
    for (int o = 0; o < 2; o++) {
      double x, y, z;
      pos(o, t, &x, &y, &z);
      bprintf(&b, "%d,%d,%.17g,%.17g,%.17g,%g\n", o + 7, t, x, y, z, br(o, t, arg));
    }
  return parse(&b, "truth.csv");
}

static inline double dark_from(int o, int t_us, double b_dark_from_t)
{
  return (o == 1 && t_us >= b_dark_from_t) ? 0.0 : 1.0;
}

/* Truth with B dark from b_dark_from_t us on (1e9: never). */
static inline elfm_table *make_truth(double b_dark_from_t)
{
  return make_truth_with(dark_from, b_dark_from_t);
}

/* Track rows for object o over frames [f0, f1] with id, offset, and frames
 * [g0, g1] as gap-closing fills (raw empty, position junk). */
static inline void add_track(buf_t *b, int id, int o, int f0, int f1, double dx, double dy,
                             double dz, int g0, int g1)
{
  for (int f = f0; f <= f1; f++) {
    double x, y, z;
    pos(o, frame_t(f), &x, &y, &z);
    if (f >= g0 && f <= g1)
      bprintf(b, "%d,%d,%.0f,%.17g,%.17g,%.17g,,,,0,0,0,1\n", id, f, frame_t(f), x + 50, y, z);
    else
      bprintf(b, "%d,%d,%.0f,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0.001,0,0,1\n", id, f,
              frame_t(f), x + dx, y + dy, z + dz, x + dx, y + dy, z + dz);
  }
}

/* tracks.csv's header (SPEC §5) */
#define TRACK_HEADER \
  "track_id,frame,t_us,x_um,y_um,z_um,raw_x_um,raw_y_um,raw_z_um,vx_um_per_ms,vy_um_per_ms," \
  "vz_um_per_ms,intensity\n"

#endif
