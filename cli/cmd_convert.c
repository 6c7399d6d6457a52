/* cmd_convert.c — eventlfm convert IN OUT [--from-us A] [--to-us B]
 *                 [--format evt3|csv] [--geometry WxH]
 *
 * Streams any readable event file into EVT 3.0 or CSV, optionally only the
 * events with A <= t_us < B. On an input error the writer is still closed
 * properly, so OUT is a valid file holding everything before the error,
 * and the exit code is 1. */
#include <getopt.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"

typedef struct convert_options {
  const char *in, *out;
  int64_t from_us, to_us;
  int have_from, have_to;
  elfm_event_format fmt;
  int width, height;
} convert_options;

static void usage(FILE *f)
{
  fprintf(f,
          "usage: eventlfm convert IN OUT [--from-us A] [--to-us B] [--format evt3|csv]\n"
          "                        [--geometry WxH]\n"
          "\n"
          "Convert an event file (EVT 3.0/2.0/2.1 RAW, DAT, CSV) to EVT 3.0 RAW or CSV,\n"
          "streaming. The output format follows OUT's extension (.raw -> evt3, .csv -> csv)\n"
          "unless --format is given.\n"
          "\n"
          "  --from-us A      keep events with t_us >= A\n"
          "  --to-us B        keep events with t_us < B\n"
          "  --format F       evt3 or csv\n"
          "  --geometry WxH   sensor size when IN has none (DAT, CSV); without it an EVT3\n"
          "                   output gets the smallest geometry holding all events\n"
          "  -h, --help       this text\n");
}

static int ends_with(const char *s, const char *suffix)
{
  size_t a = strlen(s), b = strlen(suffix);
  return a >= b && !strcmp(s + a - b, suffix);
}

/* Keep only events and triggers with t < to_us; returns 1 once the chunk
 * reached to_us (nothing later can follow, times being sorted). */
static int cut_at(elfm_event_chunk *c, int64_t to_us)
{
  int done = 0;
  size_t n = c->n;
  while (n > 0 && c->t_us[n - 1] >= to_us) {
    n--;
    done = 1;
  }
  c->n = n;
  size_t k = 0;
  for (size_t i = 0; i < c->n_trig; i++) {
    if (c->trig[i].t_us < to_us) c->trig[k++] = c->trig[i];
    else done = 1;
  }
  c->n_trig = k;
  return done;
}

/* Largest x and y of the file (one streaming pass), for a geometry. */
static int scan_extent(const char *path, int *w, int *h, elfm_event_chunk *c)
{
  elfm_error err;
  elfm_reader *r;
  if (elfm_reader_open(path, NULL, &r, &err) != ELFM_OK) return cli_fail("convert", &err);
  int mx = 0, my = 0;
  for (;;) {
    if (elfm_reader_read(r, c, &err) != ELFM_OK) {
      elfm_reader_close(r);
      return cli_fail("convert", &err);
    }
    if (!c->n && !c->n_trig) break;
    for (size_t i = 0; i < c->n; i++) {
      if (c->x[i] > mx) mx = c->x[i];
      if (c->y[i] > my) my = c->y[i];
    }
  }
  elfm_reader_close(r);
  *w = mx + 1;
  *h = my + 1;
  return CLI_OK;
}

int cmd_convert(int argc, char **argv)
{
  convert_options o;
  memset(&o, 0, sizeof o);
  static const struct option longopts[] = {
      {"from-us", required_argument, NULL, 'f'},
      {"to-us", required_argument, NULL, 't'},
      {"format", required_argument, NULL, 'F'},
      {"geometry", required_argument, NULL, 'g'},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0},
  };
  int ch;
  optind = 1;
  while ((ch = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
    switch (ch) {
    case 'f':
      if (!cli_parse_int64("convert", "--from-us", optarg, &o.from_us)) return CLI_USAGE;
      o.have_from = 1;
      break;
    case 't':
      if (!cli_parse_int64("convert", "--to-us", optarg, &o.to_us)) return CLI_USAGE;
      o.have_to = 1;
      break;
    case 'F':
      o.fmt = elfm_format_from_name(optarg);
      if (o.fmt != ELFM_FMT_EVT3 && o.fmt != ELFM_FMT_CSV)
        return cli_message("convert", CLI_USAGE, "--format must be evt3 or csv, got '%s'", optarg);
      break;
    case 'g':
      if (!cli_parse_geometry(optarg, &o.width, &o.height))
        return cli_message("convert", CLI_USAGE, "--geometry expects WIDTHxHEIGHT, got '%s'",
                           optarg);
      break;
    case 'h': usage(stdout); return CLI_OK;
    default: usage(stderr); return CLI_USAGE;
    }
  }
  if (optind != argc - 2) {
    usage(stderr);
    return CLI_USAGE;
  }
  o.in = argv[optind];
  o.out = argv[optind + 1];
  if (o.have_from && o.have_to && o.to_us <= o.from_us)
    return cli_message("convert", CLI_USAGE, "--to-us (%" PRId64 ") must exceed --from-us (%" PRId64 ")",
                       o.to_us, o.from_us);
  if (o.fmt == ELFM_FMT_UNKNOWN) {
    if (ends_with(o.out, ".raw")) o.fmt = ELFM_FMT_EVT3;
    else if (ends_with(o.out, ".csv")) o.fmt = ELFM_FMT_CSV;
    else
      return cli_message("convert", CLI_USAGE,
                         "cannot tell the output format from '%s': use .raw/.csv or --format",
                         o.out);
  }
  /* Writing over the input would destroy it before it is read. */
  struct stat si, so;
  if (stat(o.in, &si) == 0 && stat(o.out, &so) == 0 && si.st_dev == so.st_dev &&
      si.st_ino == so.st_ino)
    return cli_message("convert", CLI_USAGE, "output '%s' is the input file", o.out);

  elfm_error err;
  elfm_error_clear(&err);
  elfm_reader_options ropt = {o.width, o.height, 0};
  elfm_reader *r = NULL;
  if (elfm_reader_open(o.in, &ropt, &r, &err) != ELFM_OK) return cli_fail("convert", &err);
  elfm_event_chunk *c = elfm_chunk_create((size_t)1 << 18, &err);
  if (!c) {
    elfm_reader_close(r);
    return cli_fail("convert", &err);
  }
  int w = elfm_reader_width(r), h = elfm_reader_height(r);
  if (!w && o.fmt == ELFM_FMT_EVT3) {
    int rc = scan_extent(o.in, &w, &h, c);
    if (rc != CLI_OK) {
      elfm_reader_close(r);
      elfm_chunk_free(c);
      return rc;
    }
    cli_message("convert", 0, "note: %s has no geometry; writing %dx%d (use --geometry to set it)",
                o.in, w, h);
  }
  elfm_writer *wr = NULL;
  if (elfm_writer_open(o.out, o.fmt, w, h, &wr, &err) != ELFM_OK) {
    elfm_reader_close(r);
    elfm_chunk_free(c);
    return cli_fail("convert", &err);
  }
  int rc = CLI_OK;
  if (o.have_from && elfm_reader_seek_us(r, o.from_us, &err) != ELFM_OK) rc = cli_fail("convert", &err);
  int64_t written = 0, dropped_trig = 0;
  int tty = isatty(STDERR_FILENO);
  double t_report = cli_now_s() + 2.0;
  while (rc == CLI_OK) {
    elfm_status st = elfm_reader_read(r, c, &err);
    /* Events decoded before an input error are still written. */
    int done = o.have_to && cut_at(c, o.to_us);
    if (c->n || c->n_trig) {
      elfm_error werr;
      if (elfm_writer_write(wr, c, &werr) != ELFM_OK) {
        rc = cli_fail("convert", &werr);
        break;
      }
      written += (int64_t)c->n;
      dropped_trig += o.fmt == ELFM_FMT_CSV ? (int64_t)c->n_trig : 0;
    }
    if (st != ELFM_OK) {
      rc = cli_fail("convert", &err);
      break;
    }
    if (done || (!c->n && !c->n_trig)) break;
    if (tty && cli_now_s() > t_report) {
      fprintf(stderr, "\reventlfm convert: %.1f M events...", 1e-6 * (double)written);
      t_report = cli_now_s() + 2.0;
    }
  }
  elfm_reader_close(r);
  elfm_chunk_free(c);
  if (elfm_writer_close(wr, &err) != ELFM_OK && rc == CLI_OK) rc = cli_fail("convert", &err);
  if (rc == CLI_OK)
    fprintf(stderr, "%seventlfm convert: %" PRId64 " events -> %s (%s)\n", tty ? "\r" : "", written,
            o.out, elfm_format_name(o.fmt));
  if (dropped_trig)
    cli_message("convert", 0, "note: %" PRId64 " trigger edges not written (CSV has no place for them)",
                dropped_trig);
  return rc;
}
