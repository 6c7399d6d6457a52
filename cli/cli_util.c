/* cli_util.c — helpers shared by the subcommands (see cli.h). */
#include "cli.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

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

/* The whole of s a finite number: 1 and *out, else 0 (no message). */
static int finite_number(const char *s, double *out)
{
  char *end = NULL;
  errno = 0;
  double v = s ? strtod(s, &end) : 0.0;
  if (!s || end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) return 0;
  *out = v;
  return 1;
}

int cli_parse_double(const char *cmd, const char *opt, const char *s, double *out)
{
  if (finite_number(s, out)) return 1;
  cli_message(cmd, CLI_USAGE, "%s expects a finite number, got '%s'", opt, s ? s : "");
  return 0;
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
    {"exp", ELFM_REPR_EXP}, {"lin", ELFM_REPR_LIN}, {"count", ELFM_REPR_COUNT},
    {"integral", ELFM_REPR_INTEGRAL}};
static const name_value polarity_names[] = {
    {"both", ELFM_POL_BOTH}, {"on", ELFM_POL_ON}, {"off", ELFM_POL_OFF}, {"signed", ELFM_POL_SIGNED}};
static const name_value path_names[] = {
    {"auto", ELFM_PATH_AUTO}, {"dense", ELFM_PATH_DENSE}, {"sparse", ELFM_PATH_SPARSE}};
static const name_value ghost_names[] = {
    {"none", ELFM_GHOST_THR_NONE}, {"abs", ELFM_GHOST_THR_ABS},
    {"frac", ELFM_GHOST_THR_FRAC_MAX}, {"mad", ELFM_GHOST_THR_MAD}};
/* --start: ELFM_START_AT_TIME is the library's (--from-us), not a name */
static const name_value start_names[] = {{"first", ELFM_START_FIRST_EVENT},
                                         {"trigger", ELFM_START_FIRST_TRIGGER},
                                         {"each-trigger", ELFM_START_EACH_TRIGGER}};
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

const char *cli_start_name(elfm_frame_start v)
{ return name_of(start_names, N_OF(start_names), (int)v); }
int cli_check_trigger_start(const char *cmd, const elfm_framer_options *fo, const char *file,
                            int64_t volumes, int64_t edges)
{
  if (volumes > 0 ||
      (fo->start != ELFM_START_FIRST_TRIGGER && fo->start != ELFM_START_EACH_TRIGGER))
    return CLI_OK;
  if (edges == 0)
    return cli_message(cmd, CLI_FAIL, "--start %s: %s has no trigger edge, so no window opened",
                       cli_start_name(fo->start), file);
  if (fo->trigger_channel >= 0)
    return cli_message(cmd, CLI_FAIL,
                       "--start %s: %s has %lld trigger edges but no rising one on channel %d "
                       "(--trigger-channel), so no window opened",
                       cli_start_name(fo->start), file, (long long)edges, fo->trigger_channel);
  return cli_message(cmd, CLI_FAIL,
                     "--start %s: %s has %lld trigger edges but no rising one before its last "
                     "event, so no window opened", cli_start_name(fo->start), file,
                     (long long)edges);
}

void cli_note_no_events(const char *cmd, const char *file, int64_t from_us, int64_t to_us,
                        int64_t events)
{
  if (events > 0) return;
  if (from_us == INT64_MIN && to_us == INT64_MAX) {
    fprintf(stderr, "eventlfm %s: note: %s holds no events: no window opened\n", cmd, file);
    return;
  }
  char lo[32] = "its start", hi[32] = "its end";
  if (from_us != INT64_MIN) snprintf(lo, sizeof lo, "%lld us", (long long)from_us);
  if (to_us != INT64_MAX) snprintf(hi, sizeof hi, "%lld us", (long long)to_us);
  fprintf(stderr,
          "eventlfm %s: note: no event of %s lies in --from-us / --to-us (%s to %s): no window "
          "opened (eventlfm info %s gives its first and last event times)\n",
          cmd, file, lo, hi, file);
}

elfm_status cli_frames_csv_header(FILE *f, const char *path, int with_detections, elfm_error *err)
{
  if (fputs(with_detections ? "frame,t_us,t_start_us,t_end_us,n_events,n_detections\n"
                            : "frame,t_us,t_start_us,t_end_us,n_events\n", f) < 0)
    return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

elfm_status cli_frames_csv_row(FILE *f, const char *path, const elfm_volume *v, int n_detections,
                               elfm_error *err)
{
  int k = fprintf(f, "%" PRId64 ",%" PRId64 ",%" PRId64 ",%" PRId64 ",%zu", v->frame, v->t_us,
                  v->t_start_us, v->t_end_us, v->n_events);
  if (k >= 0) k = n_detections >= 0 ? fprintf(f, ",%d\n", n_detections) : fputs("\n", f);
  if (k < 0) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  return ELFM_OK;
}

const char *cli_repr_name(elfm_repr v) { return name_of(repr_names, N_OF(repr_names), (int)v); }
const char *cli_polarity_name(elfm_polarity v)
{ return name_of(polarity_names, N_OF(polarity_names), (int)v); }
const char *cli_refocus_path_name(elfm_refocus_path v)
{ return name_of(path_names, N_OF(path_names), (int)v); }
const char *cli_ghost_threshold_name(elfm_ghost_threshold v)
{ return name_of(ghost_names, N_OF(ghost_names), (int)v); }

/* ---- the shared reconstruction options (cli.h) ---- */

/* The library's ranges (elfm_framer_options_check, elfm_recon_layout),
 * checked here too so that a bad value is a usage error naming the option
 * rather than a run failure naming a struct field. */
#define DT_US_MIN 50
#define DT_US_MAX 10000000
#define THREADS_MAX 1024
#define BATCH_MAX 4096

/* A 64-bit integer option in lo..hi; range: how the message states it. */
static int int64_in(const char *cmd, const char *opt, const char *s, int64_t lo, int64_t hi,
                    const char *range, int64_t *out)
{
  int64_t v;
  if (!cli_parse_int64(cmd, opt, s, &v)) return 0;
  if (v < lo || v > hi) {
    cli_message(cmd, CLI_USAGE, "%s must be %s, not '%s'", opt, range, s);
    return 0;
  }
  *out = v;
  return 1;
}

int cli_parse_int_in(const char *cmd, const char *opt, const char *s, int lo, int hi,
                     const char *range, int *out)
{
  int64_t v;
  if (!int64_in(cmd, opt, s, lo, hi, range, &v)) return 0;
  *out = (int)v;
  return 1;
}

int cli_parse_on_off(const char *cmd, const char *opt, const char *s, int *out)
{
  if (!strcmp(s, "on")) *out = 1;
  else if (!strcmp(s, "off")) *out = 0;
  else {
    cli_message(cmd, CLI_USAGE, "%s must be on or off, not '%s'", opt, s);
    return 0;
  }
  return 1;
}

int cli_parse_double_in(const char *cmd, const char *opt, const char *s, double lo, int lo_open,
                        double hi, const char *range, double *out)
{
  double v;
  if (!cli_parse_double(cmd, opt, s, &v)) return 0;
  if (!(lo_open ? v > lo : v >= lo) || !(v <= hi)) {
    cli_message(cmd, CLI_USAGE, "%s must be %s, not '%s'", opt, range, s);
    return 0;
  }
  *out = v;
  return 1;
}

#define GHOST_ITEMS "none, abs[:V], frac[:F], mad[:K] or agree:F"

/* One --ghost item (of the list `all`): none, abs[:V], frac[:F], mad[:K] or
 * agree:F. A mode without a value takes --ghost-value's (checked at the end). */
static int parse_ghost_item(const char *cmd, const char *item, const char *all, cli_recon_parse *p)
{
  elfm_refocus_options *r = &p->ro->refocus;
  char name[16];
  const char *colon = strchr(item, ':');
  size_t len = colon ? (size_t)(colon - item) : strlen(item);
  if (len == 0 || len >= sizeof name) goto bad;
  memcpy(name, item, len);
  name[len] = '\0';
  if (!strcmp(name, "none")) {
    if (colon) goto bad;
    /* none: no ghost suppression at all, the agreement rule included */
    r->threshold = ELFM_GHOST_THR_NONE;
    r->agree_frac = 0;
    return 1;
  }
  double v = 0;
  if (!strcmp(name, "agree")) {
    if (!colon) goto bad;
    if (!finite_number(colon + 1, &v) || !(v >= 0 && v <= 1)) {
      cli_message(cmd, CLI_USAGE, "--ghost agree:F must be a number 0..1, not '%s'", item);
      return 0;
    }
    r->agree_frac = v;
    return 1;
  }
  int mode = 0;
  for (size_t i = 0; i < N_OF(ghost_names); i++)
    if (ghost_names[i].value != ELFM_GHOST_THR_NONE && !strcmp(name, ghost_names[i].name))
      mode = ghost_names[i].value;
  if (!mode) goto bad;
  r->threshold = (elfm_ghost_threshold)mode;
  if (!colon) return 1;
  const int frac = mode == ELFM_GHOST_THR_FRAC_MAX;
  if (!finite_number(colon + 1, &v) || !(v >= 0) || (frac && !(v <= 1))) {
    cli_message(cmd, CLI_USAGE, "--ghost %s:%s must be a number %s, not '%s'", name,
                mode == ELFM_GHOST_THR_ABS ? "V" : frac ? "F" : "K", frac ? "0..1" : ">= 0", item);
    return 0;
  }
  r->threshold_value = v;
  p->ghost_value_given = 1;
  return 1;
bad:
  if (strcmp(item, all))
    cli_message(cmd, CLI_USAGE, "--ghost: '%s' (in '%s') is not " GHOST_ITEMS, item, all);
  else
    cli_message(cmd, CLI_USAGE, "--ghost: '%s' is not " GHOST_ITEMS, item);
  return 0;
}

/* --ghost: a comma list of items, applied in order. */
static int parse_ghost(const char *cmd, const char *s, cli_recon_parse *p)
{
  char buf[256];
  if (cli_path_fmt(buf, sizeof buf, "%s", s) != 0) {
    cli_message(cmd, CLI_USAGE, "--ghost: '%.40s...' is too long", s);
    return 0;
  }
  char *item = buf;
  for (;;) {
    char *comma = strchr(item, ',');
    if (comma) *comma = '\0';
    if (!parse_ghost_item(cmd, item, s, p)) return 0;
    if (!comma) return 1;
    item = comma + 1;
  }
}

int cli_parse_recon_option(const char *cmd, int code, const char *arg, cli_recon_parse *p)
{
  elfm_recon_options *ro = p->ro;
  elfm_framer_options *fo = &ro->framer;
  switch (code) {
  case CLI_RO_DT:
    return int64_in(cmd, "--dt-us", arg, DT_US_MIN, DT_US_MAX, "50..10000000", &fo->dt_us);
  case CLI_RO_STRIDE:
    /* <= dt is checked at the end: --dt-us may come after */
    return int64_in(cmd, "--stride-us", arg, 0, DT_US_MAX, "0 (= dt) or 1..dt", &fo->stride_us);
  case CLI_RO_TAU:
    p->tau_given = 1;
    return cli_parse_double_in(cmd, "--tau-us", arg, 0, 1, HUGE_VAL, "> 0", &fo->tau_us);
  case CLI_RO_TAU_BRIGHT:
    p->tau_bright_given = 1;
    return cli_parse_double_in(cmd, "--tau-bright-us", arg, 0, 1, HUGE_VAL, "> 0",
                               &fo->tau_bright_us);
  case CLI_RO_REPR: return cli_parse_repr(cmd, arg, &fo->repr);
  case CLI_RO_TRIG_CH:
    return cli_parse_int_in(cmd, "--trigger-channel", arg, -1, 255, "-1 (any) .. 255", &fo->trigger_channel);
  case CLI_RO_START: {
    int v = 0;
    if (!parse_name(cmd, "--start", arg, start_names, N_OF(start_names), &v)) return 0;
    fo->start = (elfm_frame_start)v;
    return 1;
  }
  case CLI_RO_OFF_WEIGHT:
    return cli_parse_double_in(cmd, "--off-weight", arg, 0, 1, 100, "in (0, 100]", &fo->off_weight);
  case CLI_RO_ISTART: {
    double ms;
    if (!cli_parse_double_in(cmd, "--integral-start-ms", arg, 0, 0, 1e7, "0..10000000", &ms)) return 0;
    ro->integral_start_us = (int64_t)llround(ms * 1000);
    p->istart_given = 1;
    return 1;
  }
  case CLI_RO_ISTART_AGE: {
    double ms;
    if (!cli_parse_double_in(cmd, "--integral-start-age-ms", arg, 0, 0, 1e7, "0..10000000", &ms))
      return 0;
    ro->integral_start_age_us = (int64_t)llround(ms * 1000);
    p->istart_age_given = 1;
    return 1;
  }
  case CLI_RO_POLARITY:
    p->polarity_given = 1;
    return cli_parse_polarity(cmd, arg, &fo->polarity);
  case CLI_RO_MEDIAN: {
    int m;
    if (!cli_parse_int(cmd, "--median", arg, &m)) return 0;
    if (m != 0 && m != 3 && m != 5) {
      cli_message(cmd, CLI_USAGE, "--median must be 0, 3 or 5, not '%s'", arg);
      return 0;
    }
    ro->median = m;
    return 1;
  }
  case CLI_RO_BLUR: return cli_parse_int_in(cmd, "--blur-px", arg, 0, 2, "0, 1 or 2", &ro->blur_px);
  case CLI_RO_FROM: return cli_parse_int64(cmd, "--from-us", arg, &ro->from_us);
  case CLI_RO_TO: return cli_parse_int64(cmd, "--to-us", arg, &ro->to_us);
  case CLI_RO_PATH: return cli_parse_refocus_path(cmd, arg, &ro->refocus.path);
  case CLI_RO_GHOST: return parse_ghost(cmd, arg, p);
  case CLI_RO_GHOST_VALUE:
    /* frac's <= 1 is checked at the end: the mode may come after */
    if (!cli_parse_double_in(cmd, "--ghost-value", arg, 0, 0, HUGE_VAL, ">= 0", &ro->refocus.threshold_value))
      return 0;
    p->ghost_value_given = p->ghost_value_option = 1;
    return 1;
  case CLI_RO_AGREE:
    return cli_parse_double_in(cmd, "--agree", arg, 0, 0, 1, "0..1", &ro->refocus.agree_frac);
  case CLI_RO_THREADS:
    return cli_parse_int_in(cmd, "--threads", arg, 0, THREADS_MAX, "0..1024 (0: all)", &ro->threads);
  case CLI_RO_BATCH:
    return cli_parse_int_in(cmd, "--batch", arg, 0, BATCH_MAX, "0..4096 (0: 2 x threads)", &ro->batch);
  case CLI_RO_ZMIN:
  case CLI_RO_ZMAX:
  case CLI_RO_ZSTEP: {
    /* the checks between them and the calibration's: cli_apply_planes */
    static const char *const name[3] = {"--z-min-um", "--z-max-um", "--z-step-um"};
    const int k = code - CLI_RO_ZMIN;
    p->z_given |= 1 << k;
    return k == 2 ? cli_parse_double_in(cmd, name[k], arg, 1e-3, 0, 1e4, "0.001..10000", &p->z_um[k])
                  : cli_parse_double_in(cmd, name[k], arg, -1e4, 0, 1e4, "-10000..10000", &p->z_um[k]);
  }
  default: return -1;
  }
}

int cli_check_recon_options(const char *cmd, const cli_recon_parse *p)
{
  elfm_framer_options *fw = &p->ro->framer;
  if (fw->repr == ELFM_REPR_INTEGRAL) {
    /* The commands' defaults (a 1 ms decay, ON events for track) are the
     * time surface's; the integral needs both polarities and a long leak. */
    if (!p->polarity_given) fw->polarity = ELFM_POL_SIGNED;
    if (!p->tau_given) fw->tau_us = ELFM_INTEGRAL_TAU_US;
    /* a level above 0 (an object there) leaks more slowly (elfm_frames.h) */
    if (!p->tau_bright_given) fw->tau_bright_us = ELFM_INTEGRAL_TAU_BRIGHT_FACTOR * fw->tau_us;
    /* and starts from the levels the recording's first 2 x leak give
     * (elfm_frames.h; why 2 x and 20 ms: docs/recon.md "The integral's
     * start") */
    if (!p->istart_given) p->ro->integral_start_us = (int64_t)llround(2 * fw->tau_us);
    if (!p->istart_age_given) p->ro->integral_start_age_us = ELFM_INTEGRAL_START_AGE_US;
  } else if (p->istart_given || p->istart_age_given || p->tau_bright_given) {
    cli_message(cmd, CLI_USAGE,
                "--integral-start-ms, --integral-start-age-ms and --tau-bright-us need --repr integral");
    return 0;
  }
  const elfm_recon_options *ro = p->ro;
  const elfm_framer_options *fo = &ro->framer;
  const elfm_refocus_options *r = &ro->refocus;
  const char *mode = cli_ghost_threshold_name(r->threshold);
  int ok = 0;
  if (fo->stride_us > fo->dt_us)
    cli_message(cmd, CLI_USAGE, "--stride-us %" PRId64 " is longer than the window (--dt-us %" PRId64 ")",
                fo->stride_us, fo->dt_us);
  else if (ro->from_us >= ro->to_us)
    cli_message(cmd, CLI_USAGE, "--from-us %" PRId64 " is not before --to-us %" PRId64,
                ro->from_us, ro->to_us);
  else if (r->threshold == ELFM_GHOST_THR_NONE && p->ghost_value_option)
    cli_message(cmd, CLI_USAGE, "--ghost-value needs --ghost abs, frac or mad");
  else if (r->threshold != ELFM_GHOST_THR_NONE && !p->ghost_value_given)
    cli_message(cmd, CLI_USAGE, "--ghost %s needs a value: --ghost %s:V or --ghost-value V", mode, mode);
  else if (r->threshold == ELFM_GHOST_THR_FRAC_MAX && !(r->threshold_value <= 1))
    cli_message(cmd, CLI_USAGE, "--ghost frac needs a fraction 0..1 of the maximum, not %g",
                r->threshold_value);
  else
    ok = 1;
  if (!ok) return 0;
  /* The library's own checks, for anything the above missed. */
  elfm_error err;
  elfm_error_clear(&err);
  int threads, slots;
  if (elfm_framer_options_check(fo, &err) != ELFM_OK ||
      elfm_recon_layout(ro, &threads, &slots, &err) != ELFM_OK) {
    cli_fail(cmd, &err);
    return 0;
  }
  return 1;
}

/* The ghost rules of `r` as --ghost would give them ("agree:0.3", "none"). */
static void ghost_text(const elfm_refocus_options *r, char *out, size_t n)
{
  int k = 0;
  out[0] = '\0';
  if (r->threshold != ELFM_GHOST_THR_NONE)
    k = snprintf(out, n, "%s:%g", cli_ghost_threshold_name(r->threshold), r->threshold_value);
  if (r->agree_frac > 0 && k >= 0 && (size_t)k < n)
    snprintf(out + k, n - (size_t)k, "%sagree:%g", k ? "," : "", r->agree_frac);
  if (!out[0]) snprintf(out, n, "none");
}

void cli_recon_options_json(cJSON *par, const elfm_recon_options *ro)
{
  const elfm_framer_options *fo = &ro->framer;
  cJSON_AddNumberToObject(par, "dt_us", (double)fo->dt_us);
  cJSON_AddNumberToObject(par, "stride_us", (double)(fo->stride_us ? fo->stride_us : fo->dt_us));
  cJSON_AddStringToObject(par, "repr", cli_repr_name(fo->repr));
  cJSON_AddStringToObject(par, "start", cli_start_name(fo->start));
  cJSON_AddNumberToObject(par, "trigger_channel", fo->trigger_channel);
  cJSON_AddNumberToObject(par, "tau_us", fo->tau_us);
  cJSON_AddStringToObject(par, "polarity", cli_polarity_name(fo->polarity));
  cJSON_AddNumberToObject(par, "off_weight", fo->off_weight);
  cJSON_AddNumberToObject(par, "tau_bright_us",
                          fo->tau_bright_us > 0 ? fo->tau_bright_us : fo->tau_us);
  cJSON_AddNumberToObject(par, "integral_start_ms", (double)ro->integral_start_us * 1e-3);
  cJSON_AddNumberToObject(par, "integral_start_age_ms", (double)ro->integral_start_age_us * 1e-3);
  cJSON_AddNumberToObject(par, "median", ro->median);
  cJSON_AddNumberToObject(par, "blur_px", ro->blur_px);
  cJSON_AddStringToObject(par, "path", cli_refocus_path_name(ro->refocus.path));
  cJSON_AddStringToObject(par, "ghost_threshold", cli_ghost_threshold_name(ro->refocus.threshold));
  cJSON_AddNumberToObject(par, "ghost_threshold_value", ro->refocus.threshold_value);
  cJSON_AddNumberToObject(par, "ghost_agree_frac", ro->refocus.agree_frac);
}

cJSON *cli_summary_start(const char *calib, const char *key, const char *path,
                         const elfm_error *run_err, const elfm_recon_options *ro, cJSON **par)
{
  cJSON *root = cJSON_CreateObject(), *in = cJSON_AddObjectToObject(root, "input");
  cJSON_AddStringToObject(in, "calib", calib);
  cJSON_AddStringToObject(in, key, path);
  if (run_err) {
    char msg[1200];
    cJSON_AddStringToObject(root, "input_error", elfm_error_format(run_err, msg, sizeof msg));
  }
  cJSON *p = cJSON_AddObjectToObject(root, "parameters");
  cli_recon_options_json(p, ro);
  if (ro->from_us != INT64_MIN) cJSON_AddNumberToObject(p, "from_us", (double)ro->from_us);
  if (ro->to_us != INT64_MAX) cJSON_AddNumberToObject(p, "to_us", (double)ro->to_us);
  *par = p;
  return root;
}

void cli_summary_timing(cJSON *root, const elfm_recon_stats *s)
{
  cJSON *t = cJSON_AddObjectToObject(root, "timing");
  cJSON_AddNumberToObject(t, "span_s", s->span_s);
  cJSON_AddNumberToObject(t, "wall_s", s->wall_s);
  cJSON_AddNumberToObject(t, "read_s", s->read_s);
  cJSON_AddNumberToObject(t, "frame_s", s->frame_s);
  cJSON_AddNumberToObject(t, "refocus_s", s->refocus_s);
  cJSON_AddNumberToObject(t, "output_s", s->callback_s);
  cJSON_AddNumberToObject(t, "events_per_s", s->events_per_s);
  cJSON_AddNumberToObject(t, "volumes_per_s", s->volumes_per_s);
  cJSON_AddNumberToObject(t, "realtime_factor", s->realtime_factor);
  cJSON_AddNumberToObject(t, "peak_rss_mb", cli_peak_rss_mb());
}

int cli_json_save(cJSON *root, const char *path, const char *cmd)
{
  elfm_error err;
  if (cli_json_write(root, path, &err) == ELFM_OK) return 1;
  cli_fail(cmd, &err);
  return 0;
}

elfm_status cli_json_write(cJSON *root, const char *path, elfm_error *err)
{
  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  if (!text) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory (JSON text)");
  FILE *f = fopen(path, "w");
  elfm_status st = ELFM_OK;
  if (!f) {
    st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot create: %s", strerror(errno));
  } else {
    fputs(text, f);
    fputc('\n', f);
    if (ferror(f) | (fclose(f) != 0))
      st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "write failed: %s", strerror(errno));
  }
  free(text);
  return st;
}

int cli_views_scale(int n, int views)
{
  if (n <= 0 || views >= 25) return n;
  const int m = (n * views + 24) / 25;
  return m < 2 ? 2 : m;
}

void cli_recon_planes(const cli_recon_parse *p, double z_um[3])
{
  for (int k = 0; k < 3; k++) z_um[k] = p->z_given & (1 << k) ? p->z_um[k] : NAN;
}

int cli_apply_planes(const char *cmd, const double z_um[3], const char *calib_path, elfm_calib *cal)
{
  elfm_error err;
  elfm_error_clear(&err);
  if (elfm_calib_set_planes(cal, z_um[0], z_um[1], z_um[2], &err) == ELFM_OK) return 1;
  char msg[1200];
  cli_message(cmd, CLI_USAGE, "--z-min-um / --z-max-um / --z-step-um with %s's planes %g..%g um "
              "step %g: %s", calib_path, cal->z_min_um, cal->z_max_um, cal->z_step_um,
              elfm_error_format(&err, msg, sizeof msg));
  return 0;
}

void cli_recon_options_usage(FILE *f, const elfm_recon_options *d)
{
  const elfm_framer_options *fo = &d->framer;
  char stride[32], threads[32], batch[32], ghost[64];
  /* 0 means "as the library chooses": say what it chooses */
  if (fo->stride_us) snprintf(stride, sizeof stride, "%" PRId64, fo->stride_us);
  else snprintf(stride, sizeof stride, "0 = dt");
  if (d->threads) snprintf(threads, sizeof threads, "%d", d->threads);
  else snprintf(threads, sizeof threads, "0 = all");
  if (d->batch) snprintf(batch, sizeof batch, "%d", d->batch);
  else snprintf(batch, sizeof batch, "0 = 2 x threads");
  ghost_text(&d->refocus, ghost, sizeof ghost);
  fprintf(f,
          "  --dt-us N            window length, 50..10000000 us (default %" PRId64 ")\n"
          "  --stride-us N        window start to start, 1..dt us (default %s)\n"
          "  --start S            where windows start: first (the first event, default) |\n"
          "                       trigger (the first rising trigger edge) | each-trigger\n"
          "                       (the first, and every rising edge ends the window it\n"
          "                       falls in and opens the next: one window per light\n"
          "                       pulse, whatever its phase; blinking objects)\n"
          "  --trigger-channel N  the trigger starts use only channel N's edges (default -1:\n"
          "                       any channel)\n"
          "  --repr R             exp | lin | count | integral (default %s; exp, lin: time\n"
          "                       surfaces; integral: each pixel's leaky sum of ON minus\n"
          "                       OFF events, its log brightness: no lead along the motion)\n"
          "  --tau-us T           time-surface decay, > 0 us (default %g; integral: the\n"
          "                       leak, default %g)\n"
          "  --tau-bright-us T    integral: the leak of a level above 0, an object there\n"
          "                       (default %g x the leak)\n"
          "  --polarity P         both | on | off | signed (default %s)\n"
          "  --off-weight W       integral: an OFF event's step over an ON event's, the\n"
          "                       sensor's OFF/ON threshold ratio (default %g)\n"
          "  --integral-start-ms T  integral: read the first T ms twice and start each\n"
          "                       pixel from the brightness its later OFF events show it\n"
          "                       had (objects in view from the start are seen whole, not\n"
          "                       only where they move to); default 2 x the leak; 0 off\n"
          "  --integral-start-age-ms A  ... scaled by exp(-A / the leak), as if they had\n"
          "                       leaked for A ms (default %g); each is held until its\n"
          "                       pixel's first event\n"
          "  --median N           median filter 0 (off) | 3 | 5 (default %d)\n"
          "  --blur-px R          binomial blur of each frame after the median, radius 0\n"
          "                       (off, recon's default) | 1 (3x3) | 2 (5x5): for dim\n"
          "                       objects (about one event per view per frame), whose\n"
          "                       events then meet where their images do; track then\n"
          "                       takes thresholds 8 / 6 / 6 unless given; track's\n"
          "                       default is auto (below)\n"
          "  --from-us T          first event time to use (windows start here)\n"
          "  --to-us T            stop before this event time\n"
          "  --path P             refocus path auto | dense | sparse (default %s)\n"
          "  --ghost G            ghost suppression, a comma list of: none (all off), abs:V,\n"
          "                       frac:F (of the maximum, 0..1), mad:K (median + K robust\n"
          "                       sigma), agree:F (a voxel needs signal in F of its views,\n"
          "                       0..1; 0 = off) (default %s)\n"
          "  --ghost-value V      the value of a bare --ghost abs, frac or mad\n"
          "  --agree F            the same as --ghost agree:F\n"
          "  --threads N          worker threads, 0..1024 (default %s)\n"
          "  --batch N            frames in flight (read, refocused or being\n"
          "                       delivered: a volume each), 0..4096\n"
          "                       (default %s); refused when they would take\n"
          "                       more than half of the machine's memory\n"
          "  --z-min-um Z, --z-max-um Z, --z-step-um S   refocus on the planes Z..Z every\n"
          "                       S um instead of the calibration's (its z.min_um,\n"
          "                       z.max_um, z.step_um; each one given replaces its own):\n"
          "                       the time goes with the number of planes\n",
          fo->dt_us, stride, cli_repr_name(fo->repr), fo->tau_us, ELFM_INTEGRAL_TAU_US,
          ELFM_INTEGRAL_TAU_BRIGHT_FACTOR, cli_polarity_name(fo->polarity), fo->off_weight,
          ELFM_INTEGRAL_START_AGE_US * 1e-3,
          d->median, cli_refocus_path_name(d->refocus.path), ghost, threads, batch);
}

int cli_bad_option(const char *cmd, int c, char *const argv[])
{
  const char *opt = argv[optind - 1];
  if (c == ':') return cli_message(cmd, CLI_USAGE, "option %s needs a value", opt);
  return cli_message(cmd, CLI_USAGE, "unknown option '%s' (see eventlfm %s --help)", opt, cmd);
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

elfm_status cli_count_events(const char *path, int64_t *n, int64_t *t_first_us,
                             int64_t *t_last_us, elfm_error *err)
{
  elfm_reader *r = NULL;
  elfm_status s = elfm_reader_open(path, NULL, &r, err);
  if (s != ELFM_OK) return s;
  elfm_event_chunk *c = elfm_chunk_create(1 << 16, err);
  if (!c) { elfm_reader_close(r); return ELFM_ERR_NOMEM; }
  *n = 0;
  *t_first_us = *t_last_us = 0;
  while ((s = elfm_reader_read(r, c, err)) == ELFM_OK && c->n > 0) {
    if (*n == 0) *t_first_us = c->t_us[0];
    *t_last_us = c->t_us[c->n - 1];
    *n += (int64_t)c->n;
  }
  elfm_chunk_free(c);
  elfm_reader_close(r);
  return s;
}

const char *cli_progress_left(char *buf, size_t n, double frac, double wall_s)
{
  if (!n) return buf;
  buf[0] = '\0';
  if (!(frac >= 0) || frac > 1) return buf;
  if (frac < 0.02 || !(wall_s > 0)) {
    snprintf(buf, n, ", %.0f %%", 100 * frac);
    return buf;
  }
  const double left_s = wall_s * (1 - frac) / frac;
  if (left_s < 90) snprintf(buf, n, ", %.0f %% (~%.0f s left)", 100 * frac, left_s);
  else if (left_s < 5400) snprintf(buf, n, ", %.0f %% (~%.0f min left)", 100 * frac, left_s / 60);
  else snprintf(buf, n, ", %.0f %% (~%.1f h left)", 100 * frac, left_s / 3600);
  return buf;
}

int cli_temp_path(char *out, size_t n, const char *prefix)
{
  const char *dir = getenv("TMPDIR");
  if (!dir || !*dir) dir = "/tmp";
  if (cli_path_fmt(out, n, "%s/%s-XXXXXX", dir, prefix) != 0) return 0;
  const int fd = mkstemp(out);
  if (fd < 0) return 0;
  close(fd);
  return 1;
}
