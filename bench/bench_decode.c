/* bench_decode.c — event decode throughput, one core, file in page cache.
 *
 *   build-DIR/bench/bench_decode [--events N] [--reps R] [--chunk C] [--dir D]
 *
 * Writes N (default 50 M) synthetic events as EVT 3.0 (the library's
 * writer), EVT 2.0 and DAT (encoded here, as a camera would) into a
 * temporary directory under D (default /tmp), reads each file once to put
 * it in the page cache, then times R full decodes through the public API
 * (elfm_reader_open/read/close) into one reused chunk of C events, and
 * prints the best and median rate in million events per second, by the
 * process's CPU time (the figure that does not depend on what else runs
 * on a shared machine) and by the wall clock. The
 * directory is removed afterwards. For scale it also prints this machine's
 * single-core memory-read bandwidth: a timed sum over a 1 GiB buffer.
 *
 * With --file PATH it instead times R decodes of that existing file
 * (any readable format), e.g. a real recording.
 *
 * Synthetic scene: a high-rate recording (about 10 events per microsecond,
 * i.e. 10 Mev/s of sensor time), half the steps a burst of 2-12 events on
 * one row at one time with one polarity (what EVT3 vectorises), half a
 * single event anywhere on a 1280x720 sensor. The file sizes per event are
 * printed so runs with other mixes can be compared.
 */
#include <dirent.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "elfm_recon.h"
#include "bench_clock.h"

#define W 1280
#define H 720

static uint64_t rng(uint64_t *s)
{
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return *s * 2685821657736338717ull;
}

/* Generator state: produces the same stream for every format. */
typedef struct gen {
  uint64_t s;
  int64_t t;
  int64_t left;
} gen;

/* Fill c with up to c->cap events (fewer at the end). */
static void gen_chunk(gen *g, elfm_event_chunk *c)
{
  c->n = 0;
  c->n_trig = 0;
  while (g->left > 0 && c->n + 12 <= c->cap) {
    uint64_t r = rng(&g->s);
    g->t += (r & 3) == 0; /* ~4 steps per microsecond */
    int y = (int)((r >> 8) % H), p = (int)((r >> 20) & 1);
    if ((r >> 21) & 1) {
      int len = 2 + (int)((r >> 22) % 11);
      int x = (int)((r >> 30) % (W - 24));
      for (int i = 0; i < len && g->left > 0; i++) {
        x += 1 + (int)((r >> (40 + i)) & 1);
        c->t_us[c->n] = g->t;
        c->x[c->n] = (uint16_t)x;
        c->y[c->n] = (uint16_t)y;
        c->p[c->n] = (uint8_t)p;
        c->n++;
        g->left--;
      }
    } else {
      c->t_us[c->n] = g->t;
      c->x[c->n] = (uint16_t)((r >> 30) % W);
      c->y[c->n] = (uint16_t)y;
      c->p[c->n] = (uint8_t)p;
      c->n++;
      g->left--;
    }
  }
}

static int write_evt3(const char *path, int64_t n, elfm_event_chunk *c)
{
  elfm_error err;
  elfm_writer *w;
  if (elfm_writer_open(path, ELFM_FMT_EVT3, W, H, &w, &err) != ELFM_OK) return -1;
  gen g = {0x9E3779B97F4A7C15ull, 913000000, n};
  while (g.left > 0) {
    gen_chunk(&g, c);
    if (elfm_writer_write(w, c, &err) != ELFM_OK) {
      elfm_writer_close(w, NULL);
      return -1;
    }
  }
  return elfm_writer_close(w, &err) == ELFM_OK ? 0 : -1;
}

/* EVT 2.0 as the camera writes it: TIME_HIGH whenever t >> 6 changes. */
static int write_evt2(const char *path, int64_t n, elfm_event_chunk *c)
{
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  fprintf(f, "%% evt 2.0\n%% format EVT2;height=%d;width=%d\n%% end\n", H, W);
  gen g = {0x9E3779B97F4A7C15ull, 913000000, n};
  int64_t th = -1;
  uint32_t *buf = malloc(sizeof(uint32_t) * 2 * c->cap);
  if (!buf) return -1;
  while (g.left > 0) {
    gen_chunk(&g, c);
    size_t k = 0;
    for (size_t i = 0; i < c->n; i++) {
      int64_t t = c->t_us[i];
      if (t >> 6 != th) {
        th = t >> 6;
        buf[k++] = (8u << 28) | (uint32_t)(th & 0x0FFFFFFF);
      }
      buf[k++] = ((uint32_t)c->p[i] << 28) | ((uint32_t)(t & 63) << 22) |
                 ((uint32_t)c->x[i] << 11) | c->y[i];
    }
    fwrite(buf, 4, k, f); /* little-endian host (x86/ARM) */
  }
  free(buf);
  return fclose(f) == 0 ? 0 : -1;
}

static int write_dat(const char *path, int64_t n, elfm_event_chunk *c)
{
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  fprintf(f, "%% Data file containing Event2D events.\n%% Version 2\n%% Width %d\n%% Height %d\n", W, H);
  fputc(0, f);
  fputc(8, f);
  gen g = {0x9E3779B97F4A7C15ull, 913000000, n};
  uint32_t *buf = malloc(sizeof(uint32_t) * 2 * c->cap);
  if (!buf) return -1;
  while (g.left > 0) {
    gen_chunk(&g, c);
    for (size_t i = 0; i < c->n; i++) {
      buf[2 * i] = (uint32_t)c->t_us[i];
      buf[2 * i + 1] = ((uint32_t)c->p[i] << 28) | ((uint32_t)c->y[i] << 14) | c->x[i];
    }
    fwrite(buf, 8, c->n, f);
  }
  free(buf);
  return fclose(f) == 0 ? 0 : -1;
}

static long long file_size(const char *path)
{
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  fseeko(f, 0, SEEK_END);
  long long s = (long long)ftello(f);
  fclose(f);
  return s;
}

/* Read the file once so the timed runs find it in the page cache. */
static void warm(const char *path)
{
  FILE *f = fopen(path, "rb");
  if (!f) return;
  static const size_t sz = (size_t)8 << 20;
  char *b = malloc(sz);
  while (b && fread(b, 1, sz, f) == sz) {
  }
  free(b);
  fclose(f);
}

/* One full decode; returns wall seconds (CPU seconds in *cpu), the count
 * in *n_out, -1 on error. */
static double decode_once(const char *path, elfm_event_chunk *c, int64_t *n_out, int64_t *check,
                          double *cpu)
{
  elfm_error err;
  elfm_reader *r;
  double t0 = bench_wall_s(), c0 = bench_cpu_s();
  if (elfm_reader_open(path, NULL, &r, &err) != ELFM_OK) {
    char buf[1200];
    fprintf(stderr, "bench_decode: %s\n", elfm_error_format(&err, buf, sizeof buf));
    return -1;
  }
  int64_t n = 0, sum = 0;
  for (;;) {
    if (elfm_reader_read(r, c, &err) != ELFM_OK) {
      char buf[1200];
      fprintf(stderr, "bench_decode: %s\n", elfm_error_format(&err, buf, sizeof buf));
      elfm_reader_close(r);
      return -1;
    }
    if (!c->n && !c->n_trig) break;
    n += (int64_t)c->n;
    /* Touch the output so the decode cannot be skipped. */
    sum += c->t_us[c->n - 1] + c->x[c->n / 2];
  }
  elfm_reader_close(r);
  double dt = bench_wall_s() - t0;
  *cpu = bench_cpu_s() - c0;
  *n_out = n;
  *check = sum;
  return dt;
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Single-core read bandwidth: sum 1 GiB of uint64, best of 3. */
static double mem_read_gbps(void)
{
  const size_t n = ((size_t)1 << 30) / sizeof(uint64_t);
  uint64_t *a = malloc(n * sizeof *a);
  if (!a) return 0;
  for (size_t i = 0; i < n; i++) a[i] = i;
  double best = 1e30;
  volatile uint64_t sink = 0;
  for (int rep = 0; rep < 3; rep++) {
    double t0 = bench_wall_s();
    uint64_t s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (size_t i = 0; i < n; i += 4) {
      s0 += a[i];
      s1 += a[i + 1];
      s2 += a[i + 2];
      s3 += a[i + 3];
    }
    double dt = bench_wall_s() - t0;
    sink += s0 + s1 + s2 + s3;
    if (dt < best) best = dt;
  }
  (void)sink;
  free(a);
  return (double)(n * sizeof(uint64_t)) / best / 1e9;
}

static void remove_dir(const char *dir)
{
  DIR *d = opendir(dir);
  if (!d) return;
  struct dirent *e;
  char p[1400];
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
    unlink(p);
  }
  closedir(d);
  rmdir(dir);
}

/* --file: time decodes of an existing file. */
static int time_file(const char *path, int reps, size_t chunk)
{
  elfm_error err;
  elfm_event_chunk *c = elfm_chunk_create(chunk, &err);
  if (!c) return 1;
  warm(path);
  double best_cpu = 1e30, best_wall = 1e30;
  int64_t n = 0, check = 0;
  for (int rep = 0; rep < reps; rep++) {
    double cpu;
    double wall = decode_once(path, c, &n, &check, &cpu);
    if (wall < 0) {
      elfm_chunk_free(c);
      return 1;
    }
    if (cpu < best_cpu) best_cpu = cpu;
    if (wall < best_wall) best_wall = wall;
  }
  long long bytes = file_size(path);
  printf("%s: %" PRId64 " events, %lld bytes (%.2f B/event); best of %d: CPU %.4f s = %.1f Mev/s, "
         "wall %.4f s = %.1f Mev/s\n",
         path, n, bytes, (double)bytes / (double)(n ? n : 1), reps, best_cpu,
         (double)n / best_cpu / 1e6, best_wall, (double)n / best_wall / 1e6);
  elfm_chunk_free(c);
  return 0;
}

int main(int argc, char **argv)
{
  int64_t n_events = 50000000;
  int reps = 5;
  size_t chunk = (size_t)1 << 16;
  const char *base = "/tmp";
  const char *only_file = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--events") && i + 1 < argc) n_events = atoll(argv[++i]);
    else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--chunk") && i + 1 < argc) chunk = (size_t)atoll(argv[++i]);
    else if (!strcmp(argv[i], "--dir") && i + 1 < argc) base = argv[++i];
    else if (!strcmp(argv[i], "--file") && i + 1 < argc) only_file = argv[++i];
    else {
      printf("usage: bench_decode [--events N] [--reps R] [--chunk C] [--dir D] [--file PATH]\n");
      return strcmp(argv[i], "--help") ? 2 : 0;
    }
  }
  if (n_events < 1000 || reps < 1 || reps > 100 || chunk < 16) {
    fprintf(stderr, "bench_decode: bad arguments\n");
    return 2;
  }
  if (only_file) return time_file(only_file, reps, chunk);
  char dir[1024];
  snprintf(dir, sizeof dir, "%s/elfm_bench_decode_XXXXXX", base);
  if (!mkdtemp(dir)) {
    perror(dir);
    return 1;
  }
  elfm_error err;
  elfm_event_chunk *c = elfm_chunk_create(chunk, &err);
  elfm_event_chunk *gc = elfm_chunk_create((size_t)1 << 20, &err);
  if (!c || !gc) return 1;

  struct {
    const char *name, *file;
    int (*write)(const char *, int64_t, elfm_event_chunk *);
  } fmts[3] = {{"EVT3", "ev.raw", write_evt3}, {"EVT2", "ev2.raw", write_evt2}, {"DAT", "ev.dat", write_dat}};

  printf("bench_decode: %" PRId64 " events per file, %d timed runs each, chunk %zu events, one thread\n",
         n_events, reps, chunk);
  int rc = 0;
  for (int k = 0; k < 3 && rc == 0; k++) {
    char path[1400];
    snprintf(path, sizeof path, "%s/%s", dir, fmts[k].file);
    double tw = bench_wall_s();
    if (fmts[k].write(path, n_events, gc) != 0) {
      fprintf(stderr, "bench_decode: cannot write %s\n", path);
      rc = 1;
      break;
    }
    tw = bench_wall_s() - tw;
    long long bytes = file_size(path);
    warm(path);
    double *times = malloc(sizeof(double) * (size_t)reps);
    double *cpus = malloc(sizeof(double) * (size_t)reps);
    int64_t n = 0, check = 0, check0 = 0;
    for (int rep = 0; rep < reps; rep++) {
      times[rep] = decode_once(path, c, &n, &check, &cpus[rep]);
      if (times[rep] < 0 || n != n_events || (rep && check != check0)) {
        fprintf(stderr, "bench_decode: %s decode failed or miscounted (%" PRId64 " events)\n",
                fmts[k].name, n);
        rc = 1;
        break;
      }
      check0 = check;
    }
    if (rc == 0) {
      qsort(times, (size_t)reps, sizeof *times, cmp_double);
      qsort(cpus, (size_t)reps, sizeof *cpus, cmp_double);
      double best = cpus[0], med = cpus[reps / 2];
      printf("%-5s %6.1f MB (%.2f B/event, written in %.1f s)\n"
             "      CPU time: best %.3f s = %6.1f Mev/s (%.2f GB/s of file), median %6.1f Mev/s\n"
             "      wall:     best %.3f s = %6.1f Mev/s, median %6.1f Mev/s\n",
             fmts[k].name, bytes / 1e6, (double)bytes / (double)n_events, tw, best,
             (double)n_events / best / 1e6, (double)bytes / best / 1e9,
             (double)n_events / med / 1e6, times[0], (double)n_events / times[0] / 1e6,
             (double)n_events / times[reps / 2] / 1e6);
    }
    free(times);
    free(cpus);
    unlink(path);
    fflush(stdout);
  }
  printf("memory read bandwidth (one core, sum over 1 GiB): %.1f GB/s\n", mem_read_gbps());
  elfm_chunk_free(c);
  elfm_chunk_free(gc);
  remove_dir(dir);
  return rc;
}
