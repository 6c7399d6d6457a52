/* cmd_info.c — eventlfm info FILE [--json] [--geometry WxH]
 *
 * Streams the file once (bounded memory) and prints its format, geometry,
 * counts, time span, mean and peak event rate (per 1 ms bin) and triggers.
 * --json prints one object whose shared figures use the names of
 * shared/data/events/reference.jsonl. Integers go out as exact JSON
 * integers (cJSON raw values), not through doubles, so sums beyond 2^53
 * stay exact. */
#include <getopt.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli.h"

typedef struct info_options {
  int json;
  int width, height;
  const char *path;
} info_options;

typedef struct info_stats {
  int64_t events, on, trig;
  int64_t t_first, t_last;
  int64_t sum_t, sum_x, sum_y; /* sum_t: exact up to 9.2e18 */
  int max_x, max_y;
  int64_t bin, bin_count, peak; /* current 1 ms bin and its count */
} info_stats;

static void usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm info FILE [--json] [--geometry WxH]\n"
          "\n"
          "Describe an event file (Prophesee RAW EVT 3.0/2.0/2.1, DAT, or CSV t_us,x,y,p):\n"
          "format, geometry, events, ON/OFF counts, first/last time, duration, mean and\n"
          "peak rate (events per ms), trigger count. A file cut short or damaged is\n"
          "described up to the damage, which is named (file, byte); the exit code is 1.\n"
          "\n"
          "  --json           one JSON object (names as in data/events/reference.jsonl)\n"
          "  --geometry WxH   sensor size for files that carry none (DAT, CSV)\n"
          "  -h, --help       this text\n");
}

static void add_int(cJSON *o, const char *key, int64_t v)
{
  char buf[32];
  snprintf(buf, sizeof buf, "%" PRId64, v);
  cJSON_AddRawToObject(o, key, buf);
}

static void accumulate(info_stats *s, const elfm_event_chunk *c)
{
  for (size_t i = 0; i < c->n; i++) {
    int64_t t = c->t_us[i];
    if (s->events == 0) {
      s->t_first = t;
      s->bin = t / 1000;
    }
    s->t_last = t;
    s->sum_t += t;
    s->sum_x += c->x[i];
    s->sum_y += c->y[i];
    s->on += c->p[i];
    if (c->x[i] > s->max_x) s->max_x = c->x[i];
    if (c->y[i] > s->max_y) s->max_y = c->y[i];
    int64_t b = t / 1000;
    if (b != s->bin) {
      if (s->bin_count > s->peak) s->peak = s->bin_count;
      s->bin = b;
      s->bin_count = 0;
    }
    s->bin_count++;
    s->events++;
  }
  s->trig += (int64_t)c->n_trig;
}

int cmd_info(int argc, char **argv)
{
  info_options o = {0};
  static const struct option longopts[] = {
      {"json", no_argument, NULL, 'j'},
      {"geometry", required_argument, NULL, 'g'},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0},
  };
  int ch;
  optind = 1;
  while ((ch = getopt_long(argc, argv, "jg:h", longopts, NULL)) != -1) {
    switch (ch) {
    case 'j': o.json = 1; break;
    case 'g':
      if (!cli_parse_geometry(optarg, &o.width, &o.height))
        return cli_message("info", CLI_USAGE, "--geometry expects WIDTHxHEIGHT, got '%s'", optarg);
      break;
    case 'h': usage(stdout); return CLI_OK;
    default: usage(stderr); return CLI_USAGE;
    }
  }
  if (optind != argc - 1) {
    usage(stderr);
    return CLI_USAGE;
  }
  o.path = argv[optind];

  elfm_error err;
  elfm_error_clear(&err);
  elfm_reader_options ropt = {o.width, o.height, 1};
  elfm_reader *r = NULL;
  if (elfm_reader_open(o.path, &ropt, &r, &err) != ELFM_OK) return cli_fail("info", &err);
  /* 256 k events (3.3 MB) per chunk: large enough to amortise the call. */
  elfm_event_chunk *c = elfm_chunk_create((size_t)1 << 18, &err);
  if (!c) {
    elfm_reader_close(r);
    return cli_fail("info", &err);
  }
  info_stats s;
  memset(&s, 0, sizeof s);
  int tty = isatty(STDERR_FILENO);
  double t_start = cli_now_s(), t_report = t_start + 2.0;
  /* A read error (a truncated or corrupt file) ends the reading; the
   * events decoded before it are still described (an acquisition cut
   * short: how much of it there is), then the error, exit 1. */
  int damaged = 0;
  for (;;) {
    if (elfm_reader_read(r, c, &err) != ELFM_OK) {
      damaged = 1;
      if (c->n || c->n_trig) accumulate(&s, c);
      break;
    }
    if (!c->n && !c->n_trig) break;
    accumulate(&s, c);
    if (tty && cli_now_s() > t_report) {
      fprintf(stderr, "\reventlfm info: %.1f M events...", 1e-6 * (double)s.events);
      t_report = cli_now_s() + 2.0;
    }
  }
  if (tty && cli_now_s() > t_start + 2.0) fputc('\n', stderr);
  if (s.bin_count > s.peak) s.peak = s.bin_count;
  int64_t backward = elfm_reader_backward_steps(r);
  const char *fmt = elfm_format_name(elfm_reader_format(r));
  int w = elfm_reader_width(r), h = elfm_reader_height(r);
  elfm_reader_close(r);
  elfm_chunk_free(c);
  if (damaged && s.events == 0) return cli_fail("info", &err);
  if (s.events == 0)
    return cli_message("info", CLI_FAIL, "%s: no events (%s header without data)", o.path, fmt);
  char damage[1200] = "";
  if (damaged) elfm_error_format(&err, damage, sizeof damage);

  int64_t dur = s.t_last - s.t_first;
  /* Mean over the span; a span under 1 ms counts as 1 ms. */
  double mean_per_ms = (double)s.events / (dur > 1000 ? (double)dur / 1000.0 : 1.0);
  if (o.json) {
    cJSON *j = cJSON_CreateObject();
    if (!j) return cli_message("info", CLI_FAIL, "out of memory");
    cJSON_AddStringToObject(j, "file", o.path);
    cJSON_AddStringToObject(j, "format", fmt);
    add_int(j, "width", w);
    add_int(j, "height", h);
    add_int(j, "events", s.events);
    add_int(j, "on_events", s.on);
    add_int(j, "off_events", s.events - s.on);
    add_int(j, "t_first_us", s.t_first);
    add_int(j, "t_last_us", s.t_last);
    add_int(j, "duration_us", dur);
    add_int(j, "sum_t", s.sum_t);
    add_int(j, "sum_x", s.sum_x);
    add_int(j, "sum_y", s.sum_y);
    add_int(j, "max_x", s.max_x);
    add_int(j, "max_y", s.max_y);
    add_int(j, "non_monotonic_steps", backward);
    cJSON_AddNumberToObject(j, "mean_rate_per_ms", mean_per_ms);
    add_int(j, "peak_rate_per_ms", s.peak);
    add_int(j, "triggers", s.trig);
    if (damaged) cJSON_AddStringToObject(j, "error", damage); /* the figures are up to it */
    char *text = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    if (!text) return cli_message("info", CLI_FAIL, "out of memory");
    printf("%s\n", text);
    cJSON_free(text);
  } else {
    printf("file        %s\n", o.path);
    printf("format      %s\n", fmt);
    if (w) printf("geometry    %dx%d\n", w, h);
    else printf("geometry    unknown (largest x %d, y %d)\n", s.max_x, s.max_y);
    printf("events      %" PRId64 " (ON %" PRId64 ", OFF %" PRId64 ")\n", s.events, s.on,
           s.events - s.on);
    printf("first t     %" PRId64 " us\n", s.t_first);
    printf("last t      %" PRId64 " us\n", s.t_last);
    printf("duration    %.6f s\n", 1e-6 * (double)dur);
    printf("mean rate   %.1f events/ms\n", mean_per_ms);
    printf("peak rate   %" PRId64 " events/ms\n", s.peak);
    printf("triggers    %" PRId64 "\n", s.trig);
    if (backward) printf("time steps back %" PRId64 "\n", backward);
    if (damaged) printf("damaged     %s (the figures above are up to it)\n", damage);
  }
  return damaged ? cli_fail("info", &err) : CLI_OK;
}
