/* cli_util.c — helpers shared by the subcommands (see cli.h). */
#include "cli.h"

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

int cli_fail(const char *cmd, const elfm_error *err)
{
  char buf[1200];
  fprintf(stderr, "eventlfm %s: %s\n", cmd, elfm_error_format(err, buf, sizeof buf));
  return CLI_FAIL;
}

int cli_message(const char *cmd, int code, const char *fmt, ...)
{
  va_list ap;
  fprintf(stderr, "eventlfm %s: ", cmd);
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
  fputc('\n', stderr);
  return code;
}

int cli_parse_double(const char *cmd, const char *opt, const char *s, double *out)
{
  char *end = NULL;
  errno = 0;
  double v = s ? strtod(s, &end) : 0.0;
  if (!s || end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) {
    cli_message(cmd, CLI_USAGE, "%s expects a finite number, got '%s'", opt, s ? s : "");
    return 0;
  }
  *out = v;
  return 1;
}

int cli_parse_int64(const char *cmd, const char *opt, const char *s, int64_t *out)
{
  char *end = NULL;
  errno = 0;
  long long v = s ? strtoll(s, &end, 10) : 0;
  if (!s || end == s || *end != '\0' || errno == ERANGE) {
    cli_message(cmd, CLI_USAGE, "%s expects an integer, got '%s'", opt, s ? s : "");
    return 0;
  }
  *out = (int64_t)v;
  return 1;
}

int cli_parse_int(const char *cmd, const char *opt, const char *s, int *out)
{
  int64_t v;
  if (!cli_parse_int64(cmd, opt, s, &v)) return 0;
  if (v < INT_MIN || v > INT_MAX) {
    cli_message(cmd, CLI_USAGE, "%s: %s is out of range", opt, s);
    return 0;
  }
  *out = (int)v;
  return 1;
}

int cli_parse_geometry(const char *s, int *w, int *h)
{
  char *end;
  long a = strtol(s, &end, 10);
  if (end == s || *end != 'x') return 0;
  const char *s2 = end + 1;
  long b = strtol(s2, &end, 10);
  if (end == s2 || *end || a < 1 || b < 1 || a > 65536 || b > 65536) return 0;
  *w = (int)a;
  *h = (int)b;
  return 1;
}

int cli_path_fmt(char *out, size_t n, const char *fmt, ...)
{
  va_list ap;
  va_start(ap, fmt);
  int k = vsnprintf(out, n, fmt, ap);
  va_end(ap);
  return k < 0 || (size_t)k >= n ? -1 : 0;
}

typedef struct {
  const char *name;
  int value;
} name_value;

static const name_value repr_names[] = {
    {"exp", ELFM_REPR_EXP}, {"lin", ELFM_REPR_LIN}, {"count", ELFM_REPR_COUNT}};
static const name_value polarity_names[] = {
    {"both", ELFM_POL_BOTH}, {"on", ELFM_POL_ON}, {"off", ELFM_POL_OFF}, {"signed", ELFM_POL_SIGNED}};
static const name_value path_names[] = {
    {"auto", ELFM_PATH_AUTO}, {"dense", ELFM_PATH_DENSE}, {"sparse", ELFM_PATH_SPARSE}};
static const name_value ghost_names[] = {
    {"none", ELFM_GHOST_THR_NONE}, {"abs", ELFM_GHOST_THR_ABS},
    {"frac", ELFM_GHOST_THR_FRAC_MAX}, {"mad", ELFM_GHOST_THR_MAD}};
#define N_OF(t) (sizeof(t) / sizeof((t)[0]))

/* Look s up in t; on failure print the choices ("a, b or c") for opt. */
static int parse_name(const char *cmd, const char *opt, const char *s, const name_value *t,
                      size_t n, int *out)
{
  for (size_t i = 0; s && i < n; i++)
    if (!strcmp(s, t[i].name)) {
      *out = t[i].value;
      return 1;
    }
  char choices[200] = "";
  size_t len = 0;
  for (size_t i = 0; i < n && len < sizeof choices; i++)
    len += (size_t)snprintf(choices + len, sizeof choices - len, "%s%s",
                            i == 0 ? "" : i + 1 == n ? " or " : ", ", t[i].name);
  cli_message(cmd, CLI_USAGE, "%s must be %s, not '%s'", opt, choices, s ? s : "");
  return 0;
}

static const char *name_of(const name_value *t, size_t n, int v)
{
  for (size_t i = 0; i < n; i++)
    if (t[i].value == v) return t[i].name;
  return "?";
}

int cli_parse_repr(const char *cmd, const char *s, elfm_repr *out)
{
  int v = 0;
  if (!parse_name(cmd, "--repr", s, repr_names, N_OF(repr_names), &v)) return 0;
  *out = (elfm_repr)v;
  return 1;
}

int cli_parse_polarity(const char *cmd, const char *s, elfm_polarity *out)
{
  int v = 0;
  if (!parse_name(cmd, "--polarity", s, polarity_names, N_OF(polarity_names), &v)) return 0;
  *out = (elfm_polarity)v;
  return 1;
}

int cli_parse_refocus_path(const char *cmd, const char *s, elfm_refocus_path *out)
{
  int v = 0;
  if (!parse_name(cmd, "--path", s, path_names, N_OF(path_names), &v)) return 0;
  *out = (elfm_refocus_path)v;
  return 1;
}

int cli_parse_ghost_threshold(const char *cmd, const char *s, elfm_ghost_threshold *out)
{
  int v = 0;
  if (!parse_name(cmd, "--ghost", s, ghost_names, N_OF(ghost_names), &v)) return 0;
  *out = (elfm_ghost_threshold)v;
  return 1;
}

const char *cli_repr_name(elfm_repr v) { return name_of(repr_names, N_OF(repr_names), (int)v); }
const char *cli_polarity_name(elfm_polarity v)
{ return name_of(polarity_names, N_OF(polarity_names), (int)v); }
const char *cli_refocus_path_name(elfm_refocus_path v)
{ return name_of(path_names, N_OF(path_names), (int)v); }
const char *cli_ghost_threshold_name(elfm_ghost_threshold v)
{ return name_of(ghost_names, N_OF(ghost_names), (int)v); }

double cli_now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double cli_peak_rss_mb(void)
{
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0.0;
  return (double)ru.ru_maxrss / 1024.0; /* Linux reports kilobytes */
}
