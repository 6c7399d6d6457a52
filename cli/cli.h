/* cli.h — what every eventlfm subcommand file shares.
 *
 * A subcommand is `int cmd_NAME(int argc, char **argv)` with argv[0] the
 * subcommand's name; it parses its options (getopt_long) into a struct,
 * calls the libraries, prints results to stdout and messages to stderr, and
 * returns the process exit code: 0 success, 1 failure, 2 usage error.
 * Every subcommand answers --help (and -h) with its usage on stdout, exit 0.
 */
#ifndef ELFM_CLI_H
#define ELFM_CLI_H

#include <getopt.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "elfm_recon.h"

#define CLI_OK 0
#define CLI_FAIL 1
#define CLI_USAGE 2

int cmd_info(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_calib(int argc, char **argv);
int cmd_calib_refine(int argc, char **argv); /* calib refine (cmd_calib_refine.c) */
/* its --help, and the frames' defaults it starts from (cmd_calib_refine_help.c) */
void calib_refine_usage(FILE *f);
void calib_refine_recon_defaults(elfm_recon_options *ro);
int cmd_simulate(int argc, char **argv);
int cmd_recon(int argc, char **argv);
int cmd_track(int argc, char **argv);
int cmd_score(int argc, char **argv);
int cmd_traces(int argc, char **argv);
int cmd_view(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_demo(int argc, char **argv);

/* Print "eventlfm CMD: <formatted error>" to stderr; returns CLI_FAIL. */
int cli_fail(const char *cmd, const elfm_error *err);
/* Print "eventlfm CMD: message" to stderr; returns `code`. */
int cli_message(const char *cmd, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Strict number parsing for options: the whole string must be a number
 * (and for ints, fit); on failure prints a usage message naming the option
 * and returns 0; on success stores the value and returns 1. */
int cli_parse_double(const char *cmd, const char *opt, const char *s, double *out);
int cli_parse_int64(const char *cmd, const char *opt, const char *s, int64_t *out);
int cli_parse_int(const char *cmd, const char *opt, const char *s, int *out);
/* A whole number in lo..hi; out of range: a usage message "OPT must be
 * RANGE, not 'S'" (range says it in words). */
int cli_parse_int_in(const char *cmd, const char *opt, const char *s, int lo, int hi,
                     const char *range, int *out);
/* A number in lo..hi (lo excluded when lo_open); out of range: a usage
 * message "OPT must be RANGE, not 'S'" (range says it in words). */
int cli_parse_double_in(const char *cmd, const char *opt, const char *s, double lo, int lo_open,
                        double hi, const char *range, double *out);

/* "on" -> 1, "off" -> 0; anything else: a usage message "OPT must be on
 * or off, not 'S'". */
int cli_parse_on_off(const char *cmd, const char *opt, const char *s, int *out);

/* "1280x720" -> 1280, 720 (both 1..65536); 1 on success, 0 otherwise. */
int cli_parse_geometry(const char *s, int *w, int *h);

/* A new empty file of this process's own, $TMPDIR/PREFIX-XXXXXX (else
 * /tmp), its path into out[n]: 1, or 0 when none could be made. The
 * caller removes it. */
int cli_temp_path(char *out, size_t n, const char *prefix);

/* snprintf for paths and labels: returns 0, or -1 when the text did not fit
 * (the caller then meets a missing file, never an overflow). */
int cli_path_fmt(char *out, size_t n, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* The reconstruction options' names, one table each, shared by recon, track
 * and bench so that a name means the same everywhere. The parsers print
 * "OPT must be a, b or c, not 'x'" (a usage error) and return 0 when s is not
 * a name; on success they store the value and return 1. The namers return
 * the name of a value ("?" for a value outside the table). */
int cli_parse_repr(const char *cmd, const char *s, elfm_repr *out);
int cli_parse_polarity(const char *cmd, const char *s, elfm_polarity *out);
int cli_parse_refocus_path(const char *cmd, const char *s, elfm_refocus_path *out);
const char *cli_repr_name(elfm_repr v);
const char *cli_start_name(elfm_frame_start v);
/* A trigger start (--start trigger / each-trigger) that opened no window
 * (`volumes` made, from the run's stats): the message naming the file, the
 * edges it had and the channel asked for, and CLI_FAIL. CLI_OK otherwise. */
int cli_check_trigger_start(const char *cmd, const elfm_framer_options *fo, const char *file,
                            int64_t volumes, int64_t edges);
/* A run that took no event (`events`, from the run's stats) from `file`
 * says so on stderr: none in the range asked for (--from-us / --to-us,
 * INT64_MIN / INT64_MAX when not given), or none at all. A note, not an
 * error: the run's outputs are valid and empty (tests/track_cli.sh), as a
 * script over many recordings wants them; but "0 volumes" alone, exit 0,
 * did not say why (sixty-first session). */
void cli_note_no_events(const char *cmd, const char *file, int64_t from_us, int64_t to_us,
                        int64_t events);

/* frames.csv, written by recon and track: one row per volume, its frame,
 * t_us, window [t_start_us, t_end_us) and events, and with n_detections >= 0
 * (track) that column too. The header says which (with_detections). */
elfm_status cli_frames_csv_header(FILE *f, const char *path, int with_detections, elfm_error *err);
elfm_status cli_frames_csv_row(FILE *f, const char *path, const elfm_volume *v, int n_detections,
                               elfm_error *err);
const char *cli_polarity_name(elfm_polarity v);
const char *cli_refocus_path_name(elfm_refocus_path v);
const char *cli_ghost_threshold_name(elfm_ghost_threshold v);

/* The reconstruction options recon and track share (--dt-us, --stride-us,
 * --tau-us, --repr, --polarity, --start, --trigger-channel, --median, --from-us, --to-us, --path,
 * --ghost, --ghost-value, --agree, --threads, --batch): one parser, one set
 * of checks and messages and one help text, so that an option means and
 * checks the same in both commands. Each command keeps its own defaults:
 * it sets them in the elfm_recon_options before parsing.
 *
 *   static const struct option opts[] = {CLI_RECON_LONG_OPTIONS, {"out", ...}, ...};
 *   cli_recon_parse rp = {.ro = &ro};
 *   while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
 *     int k = cli_parse_recon_option(cmd, c, optarg, &rp);
 *     if (k == 0) return CLI_USAGE;
 *     if (k > 0) continue;
 *     switch (c) { ...the command's own options... }
 *   }
 *   if (!cli_check_recon_options(cmd, &rp)) return CLI_USAGE;
 *
 * The getopt codes sit far above the commands' own (which start at 256). */
enum {
  CLI_RO_DT = 0x7000, CLI_RO_STRIDE, CLI_RO_TAU, CLI_RO_REPR, CLI_RO_POLARITY, CLI_RO_MEDIAN,
  CLI_RO_FROM, CLI_RO_TO, CLI_RO_PATH, CLI_RO_GHOST, CLI_RO_GHOST_VALUE, CLI_RO_AGREE,
  CLI_RO_THREADS, CLI_RO_BATCH, CLI_RO_OFF_WEIGHT, CLI_RO_ISTART, CLI_RO_ISTART_AGE,
  CLI_RO_TAU_BRIGHT, CLI_RO_START, CLI_RO_TRIG_CH, CLI_RO_ZMIN, CLI_RO_ZMAX, CLI_RO_ZSTEP,
  CLI_RO_BLUR
};
#define CLI_RECON_LONG_OPTIONS                                                                 \
  {"dt-us", required_argument, 0, CLI_RO_DT}, {"stride-us", required_argument, 0, CLI_RO_STRIDE}, \
  {"tau-us", required_argument, 0, CLI_RO_TAU}, {"repr", required_argument, 0, CLI_RO_REPR},      \
  {"polarity", required_argument, 0, CLI_RO_POLARITY},                                         \
  {"median", required_argument, 0, CLI_RO_MEDIAN},                                             \
  {"blur-px", required_argument, 0, CLI_RO_BLUR},                                              \
  {"from-us", required_argument, 0, CLI_RO_FROM}, {"to-us", required_argument, 0, CLI_RO_TO},   \
  {"path", required_argument, 0, CLI_RO_PATH}, {"ghost", required_argument, 0, CLI_RO_GHOST},   \
  {"ghost-value", required_argument, 0, CLI_RO_GHOST_VALUE},                                   \
  {"agree", required_argument, 0, CLI_RO_AGREE},                                               \
  {"threads", required_argument, 0, CLI_RO_THREADS},                                           \
  {"batch", required_argument, 0, CLI_RO_BATCH},                                               \
  {"off-weight", required_argument, 0, CLI_RO_OFF_WEIGHT},                                     \
  {"integral-start-ms", required_argument, 0, CLI_RO_ISTART},                                  \
  {"integral-start-age-ms", required_argument, 0, CLI_RO_ISTART_AGE},                          \
  {"tau-bright-us", required_argument, 0, CLI_RO_TAU_BRIGHT},                                 \
  {"start", required_argument, 0, CLI_RO_START},                                               \
  {"trigger-channel", required_argument, 0, CLI_RO_TRIG_CH},                                  \
  {"z-min-um", required_argument, 0, CLI_RO_ZMIN}, {"z-max-um", required_argument, 0, CLI_RO_ZMAX}, \
  {"z-step-um", required_argument, 0, CLI_RO_ZSTEP}

typedef struct cli_recon_parse {
  elfm_recon_options *ro;  /* the command's defaults, then the options given */
  /* A ghost threshold (--ghost abs|frac|mad) needs a value, from MODE:V or
   * --ghost-value, which may come before or after the mode: checked at the
   * end (cli_check_recon_options). */
  int ghost_value_given;   /* by MODE:V or --ghost-value */
  int ghost_value_option;  /* by --ghost-value */
  int tau_given, polarity_given; /* --repr integral has its own defaults for these */
  int tau_bright_given;          /* --tau-bright-us */
  int istart_given, istart_age_given; /* --integral-start-ms, --integral-start-age-ms */
  double z_um[3];          /* --z-min-um, --z-max-um, --z-step-um, where z_given's bit */
  int z_given;             /* 1, 2, 4 says so; the calibration's planes otherwise */
} cli_recon_parse;

/* 1: `code` is a shared option and `arg` a good value (stored in p->ro);
 * 0: it is one and `arg` is bad (message naming the option printed: a usage
 * error); -1: `code` is not a shared option (the command's own). */
int cli_parse_recon_option(const char *cmd, int code, const char *arg, cli_recon_parse *p);
/* After the options: the defaults that depend on others (--repr integral:
 * both polarities, ELFM_INTEGRAL_TAU_US, unless given), then the checks
 * between them (stride <= dt, from < to, a ghost threshold's value).
 * 1 when good; 0 after printing the message. */
int cli_check_recon_options(const char *cmd, const cli_recon_parse *p);
/* The z planes the options ask for, NaN where the calibration's stand
 * (for elfm_calib_set_planes). */
void cli_recon_planes(const cli_recon_parse *p, double z_um[3]);
/* A count of agreeing views chosen on the paper's 25, for a calibration
 * with `views`: ceil(n x views / 25), at least 2 (two views locate a
 * point), with 25 views or more n itself (track measured 7 x 7 lose with
 * the counts doubled); 0 stays 0 (off). track and calib refine. */
int cli_views_scale(int n, int views);
/* Put planes z_um (cli_recon_planes) into *cal, loaded from `calib_path`:
 * 1, or 0 after a usage message naming the options and the file. */
int cli_apply_planes(const char *cmd, const double z_um[3], const char *calib_path, elfm_calib *cal);
/* The shared options' help lines, with the command's defaults `d`. */
void cli_recon_options_usage(FILE *f, const elfm_recon_options *d);
/* The shared options' values into a summary.json "parameters" object (the
 * framer, the median, the refocus path and ghost rule), for recon and track
 * alike. */
struct cJSON;
void cli_recon_options_json(struct cJSON *par, const elfm_recon_options *ro);
/* A summary's start, as recon and traces write it: "input" {calib, key:
 * path}, "input_error" when run_err (a run cut short by its input: the
 * counts that follow are of what was read), and "parameters" holding the
 * shared options and from_us / to_us when given; *par receives it. */
struct cJSON *cli_summary_start(const char *calib, const char *key, const char *path,
                                const elfm_error *run_err, const elfm_recon_options *ro,
                                struct cJSON **par);
/* A summary's "timing" object from the driver's stats, as recon and traces
 * write it: span, wall, the read / frame / refocus / output split, the
 * rates and the peak resident memory. */
void cli_summary_timing(struct cJSON *root, const elfm_recon_stats *s);
/* Write root as indented JSON and a newline to path, then free root (also
 * on failure). Errors name the path. */
elfm_status cli_json_write(struct cJSON *root, const char *path, elfm_error *err);
/* The same, the error (if any) shown for command cmd: 1 written, 0 not. */
int cli_json_save(struct cJSON *root, const char *path, const char *cmd);

/* getopt_long's answer for an option that is not the command's (c '?') or
 * lacks its value (c ':', with ':' leading the optstring): the message
 * naming it; returns CLI_USAGE. */
int cli_bad_option(const char *cmd, int c, char *const argv[]);

/* Files and child processes (bench runs every sweep point as a child of
 * this binary; demo draws its plot with gnuplot). */

/* mkdir -p: path and its missing parents. 0, or -1 when one could not be
 * made (errno from mkdir) or the path is too long. */
int cli_mkdir_p(const char *path);
/* Whether every file a command writes into --out fits a path of PATH_MAX:
 * longest_name (with its leading '/') is the longest of them. 1 when it
 * fits; otherwise 0 and a message naming --out and the limit. Called before
 * any directory is made, so a refused --out leaves nothing behind: cut to
 * fit, the paths would name other files (and with many parts the
 * directories were made before the first file failed). */
int cli_out_fits(const char *cmd, const char *out, const char *longest_name);
/* The whole file as a NUL-terminated string (the caller frees it); NULL
 * when it cannot be read or is longer than max_bytes (a caller's bound on
 * what it is willing to parse). */
char *cli_read_text(const char *path, long max_bytes);
/* Write calibration c to out as its consumers will read it: saved beside
 * out (out.tmp), loaded back (the checks every consumer applies; c becomes
 * what was read) and moved over out only when it loads, so that a refused
 * calibration neither lands in out nor replaces the one there (`calib
 * from-optics --na 1e-300` left it there until the sixty-first session).
 * CLI_OK, or CLI_FAIL with a message naming out and, when refused, the key
 * and its range. */
int cli_calib_write(const char *cmd, elfm_calib *c, const char *out);
/* Run argv (argv[0] a path, or a name looked up on PATH when use_path) with
 * its stdout and stderr into log_path, wait for it, and kill it (by its id)
 * after timeout_s seconds (<= 0: no limit). Returns its exit code, 128 +
 * signal when a signal ended it, -1 when it could not start, -2 on timeout.
 * wall_s, peak_rss_mb (the child's peak resident memory) and cpu_s (its
 * user + system time, all threads) may be NULL. */
int cli_run_child(char *const argv[], int use_path, const char *log_path, double timeout_s,
                  double *wall_s, double *peak_rss_mb, double *cpu_s);
/* The number of events of a recording and its first and last time stamps
 * (0 when empty), streaming: memory does not grow with the file. */
elfm_status cli_count_events(const char *path, int64_t *n, int64_t *t_first_us,
                             int64_t *t_last_us, elfm_error *err);

/* Seconds of a monotonic clock (for timing figures). */
double cli_now_s(void);
/* Peak resident set size of this process in MB (0 when unknown). */
double cli_peak_rss_mb(void);
/* For a progress line: ", 62 % (~55 s left)" from how far through the input
 * a run is (frac 0..1, elfm_recon_stats.done_frac) and the wall time so
 * far, the time left at the rate so far; ", 1 %" until 2 % are done (too
 * early to say), "" when frac is unknown (< 0). Writes into buf, returns it. */
const char *cli_progress_left(char *buf, size_t n, double frac, double wall_s);

#endif
