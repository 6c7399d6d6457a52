/* test_events_common.h — helpers shared by the event I/O tests: a scratch
 * directory, raw-byte file writers (little-endian words, written by hand so
 * the tests do not trust the library's own encoders), whole-file decoding
 * into growable arrays, and a small deterministic random generator. */
#ifndef ELFM_TEST_EVENTS_COMMON_H
#define ELFM_TEST_EVENTS_COMMON_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "elfm_events.h"

typedef struct ev_list {
  int64_t *t;
  uint16_t *x, *y;
  uint8_t *p;
  size_t n, cap;
  elfm_trigger *trig;
  size_t n_trig, cap_trig;
} ev_list;

static inline void ev_push(ev_list *l, int64_t t, int x, int y, int p)
{
  if (l->n == l->cap) {
    l->cap = l->cap ? 2 * l->cap : 1024;
    l->t = realloc(l->t, l->cap * sizeof *l->t);
    l->x = realloc(l->x, l->cap * sizeof *l->x);
    l->y = realloc(l->y, l->cap * sizeof *l->y);
    l->p = realloc(l->p, l->cap);
    if (!l->t || !l->x || !l->y || !l->p) { fprintf(stderr, "out of memory\n"); exit(1); }
  }
  l->t[l->n] = t;
  l->x[l->n] = (uint16_t)x;
  l->y[l->n] = (uint16_t)y;
  l->p[l->n] = (uint8_t)p;
  l->n++;
}

static inline void ev_push_trig(ev_list *l, elfm_trigger tr)
{
  if (l->n_trig == l->cap_trig) {
    l->cap_trig = l->cap_trig ? 2 * l->cap_trig : 64;
    l->trig = realloc(l->trig, l->cap_trig * sizeof *l->trig);
    if (!l->trig) { fprintf(stderr, "out of memory\n"); exit(1); }
  }
  l->trig[l->n_trig++] = tr;
}

static inline void ev_free(ev_list *l)
{
  free(l->t);
  free(l->x);
  free(l->y);
  free(l->p);
  free(l->trig);
  memset(l, 0, sizeof *l);
}

/* Decode a whole file with chunks of `cap` events. Returns the status of
 * the last read (or open); events decoded before an error are kept. */
static inline elfm_status ev_decode_file(const char *path, const elfm_reader_options *opt, size_t cap,
                                  ev_list *out, elfm_error *err)
{
  elfm_reader *r;
  elfm_status st = elfm_reader_open(path, opt, &r, err);
  if (st != ELFM_OK) return st;
  elfm_event_chunk *c = elfm_chunk_create(cap, err);
  if (!c) { elfm_reader_close(r); return ELFM_ERR_NOMEM; }
  for (int guard = 0; guard < 100000000; guard++) {
    st = elfm_reader_read(r, c, err);
    for (size_t i = 0; i < c->n; i++) ev_push(out, c->t_us[i], c->x[i], c->y[i], c->p[i]);
    for (size_t i = 0; i < c->n_trig; i++) ev_push_trig(out, c->trig[i]);
    if (st != ELFM_OK || (!c->n && !c->n_trig)) break;
  }
  elfm_chunk_free(c);
  elfm_reader_close(r);
  return st;
}

/* Scratch directory removed by scratch_remove(). */
static inline void scratch_make(char *dir, size_t size)
{
  snprintf(dir, size, "/tmp/elfm_test_events_XXXXXX");
  if (!mkdtemp(dir)) { perror("mkdtemp"); exit(1); }
}

static inline void scratch_remove(const char *dir)
{
  DIR *d = opendir(dir);
  if (!d) return;
  struct dirent *e;
  char p[1024];
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
    unlink(p);
  }
  closedir(d);
  rmdir(dir);
}

/* A byte buffer to assemble test files. */
typedef struct bytes {
  uint8_t *b;
  size_t n, cap;
} bytes;

static inline void by_put(bytes *s, const void *src, size_t n)
{
  if (s->n + n > s->cap) {
    while (s->n + n > s->cap) s->cap = s->cap ? 2 * s->cap : 4096;
    s->b = realloc(s->b, s->cap);
    if (!s->b) { fprintf(stderr, "out of memory\n"); exit(1); }
  }
  memcpy(s->b + s->n, src, n);
  s->n += n;
}
static inline void by_str(bytes *s, const char *str) { by_put(s, str, strlen(str)); }
static inline void by_u16(bytes *s, uint32_t v)
{
  uint8_t b[2] = {(uint8_t)v, (uint8_t)(v >> 8)};
  by_put(s, b, 2);
}
static inline void by_u32(bytes *s, uint32_t v)
{
  uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
  by_put(s, b, 4);
}
static inline void by_write(const bytes *s, const char *path)
{
  FILE *f = fopen(path, "wb");
  if (!f || (s->n && fwrite(s->b, 1, s->n, f) != s->n) || fclose(f)) {
    perror(path);
    exit(1);
  }
}

static inline uint64_t rng_next(uint64_t *s)
{
  /* xorshift64*: deterministic, good enough for test data. */
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return *s * 2685821657736338717ull;
}

#endif
