/* elfm_error.h — status codes and the error object every EventLFM call fills.
 *
 * Contract (the GSL/libvips rule): a function that detects an error fills the
 * caller's elfm_error with elfm_error_set() and returns the code; a function
 * whose callee failed just returns the callee's code, leaving the message as
 * the callee wrote it. Library code never prints and never exits.
 * There is no global error state: every call takes its own elfm_error (which
 * may be NULL when the caller does not want the message).
 */
#ifndef ELFM_ERROR_H
#define ELFM_ERROR_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum elfm_status {
  ELFM_OK = 0,
  ELFM_ERR_IO,          /* open/read/write/close failed; errno text in the message */
  ELFM_ERR_FORMAT,      /* input does not follow its format (corrupt, truncated) */
  ELFM_ERR_RANGE,       /* a value outside its valid range (x beyond width, ...) */
  ELFM_ERR_INVALID,     /* a bad argument or option from the caller */
  ELFM_ERR_NOMEM,       /* allocation failed */
  ELFM_ERR_UNSUPPORTED, /* valid, but not something this build handles */
  ELFM_ERR_NUMERIC,     /* NaN/inf input, failure to converge */
  ELFM_ERR_DISPLAY      /* no display / no suitable OpenGL (viewer) */
} elfm_status;

/* Where an error was found: a byte offset in a binary file, or a 1-based
 * line in a text file; `offset` and `line` are -1 / 0 when they do not apply. */
typedef struct elfm_error {
  elfm_status code;
  int64_t offset;        /* byte offset into `file`, or -1 */
  int64_t line;          /* 1-based line of a text `file`, or 0 */
  char file[512];        /* path of the file concerned, or "" */
  char message[512];
} elfm_error;

/* Fill `err` (if not NULL) and return `code`. `file` may be NULL. */
elfm_status elfm_error_set(elfm_error *err, elfm_status code, const char *file,
                           int64_t offset, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Same, for text files: `line` is 1-based. */
elfm_status elfm_error_set_line(elfm_error *err, elfm_status code, const char *file,
                                int64_t line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Reset to ELFM_OK with empty texts. */
void elfm_error_clear(elfm_error *err);

/* Short constant name of a status ("format error", ...). */
const char *elfm_status_str(elfm_status code);

/* One human line into buf: "FILE: byte N: message", "FILE:LINE: message",
 * "FILE: message" or "message". Returns buf. */
char *elfm_error_format(const elfm_error *err, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif
