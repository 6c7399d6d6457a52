/* cli_util.c — helpers shared by the subcommands (see cli.h). */
#include "cli.h"

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
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
