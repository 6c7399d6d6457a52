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

#include <stddef.h>
#include <stdint.h>

#include "elfm_recon.h"

#define CLI_OK 0
#define CLI_FAIL 1
#define CLI_USAGE 2

int cmd_info(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_calib(int argc, char **argv);
int cmd_simulate(int argc, char **argv);
int cmd_recon(int argc, char **argv);
int cmd_track(int argc, char **argv);
int cmd_score(int argc, char **argv);
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

/* "1280x720" -> 1280, 720 (both 1..65536); 1 on success, 0 otherwise. */
int cli_parse_geometry(const char *s, int *w, int *h);

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
int cli_parse_ghost_threshold(const char *cmd, const char *s, elfm_ghost_threshold *out);
const char *cli_repr_name(elfm_repr v);
const char *cli_polarity_name(elfm_polarity v);
const char *cli_refocus_path_name(elfm_refocus_path v);
const char *cli_ghost_threshold_name(elfm_ghost_threshold v);

/* Seconds of a monotonic clock (for timing figures). */
double cli_now_s(void);
/* Peak resident set size of this process in MB (0 when unknown). */
double cli_peak_rss_mb(void);

#endif
