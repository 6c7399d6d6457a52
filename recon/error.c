/* error.c — the error object (see elfm_error.h). */
#include "elfm_error.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void set_common(elfm_error *err, elfm_status code, const char *file,
                       const char *fmt, va_list ap)
{
  err->code = code;
  if (file) {
    /* Keep the tail of a long path: the file name matters most. */
    size_t len = strlen(file);
    const char *src = len >= sizeof err->file ? file + len - (sizeof err->file - 1) : file;
    memcpy(err->file, src, strlen(src) + 1);
  } else {
    err->file[0] = '\0';
  }
  vsnprintf(err->message, sizeof err->message, fmt, ap);
}

elfm_status elfm_error_set(elfm_error *err, elfm_status code, const char *file,
                           int64_t offset, const char *fmt, ...)
{
  if (!err) return code;
  va_list ap;
  va_start(ap, fmt);
  set_common(err, code, file, fmt, ap);
  va_end(ap);
  err->offset = offset;
  err->line = 0;
  return code;
}

elfm_status elfm_error_set_line(elfm_error *err, elfm_status code, const char *file,
                                int64_t line, const char *fmt, ...)
{
  if (!err) return code;
  va_list ap;
  va_start(ap, fmt);
  set_common(err, code, file, fmt, ap);
  va_end(ap);
  err->offset = -1;
  err->line = line;
  return code;
}

void elfm_error_clear(elfm_error *err)
{
  if (!err) return;
  err->code = ELFM_OK;
  err->offset = -1;
  err->line = 0;
  err->file[0] = '\0';
  err->message[0] = '\0';
}

const char *elfm_status_str(elfm_status code)
{
  switch (code) {
  case ELFM_OK: return "ok";
  case ELFM_ERR_IO: return "I/O error";
  case ELFM_ERR_FORMAT: return "format error";
  case ELFM_ERR_RANGE: return "out of range";
  case ELFM_ERR_INVALID: return "invalid argument";
  case ELFM_ERR_NOMEM: return "out of memory";
  case ELFM_ERR_UNSUPPORTED: return "unsupported";
  case ELFM_ERR_NUMERIC: return "numerical error";
  case ELFM_ERR_DISPLAY: return "no display";
  }
  return "unknown error";
}

char *elfm_error_format(const elfm_error *err, char *buf, size_t size)
{
  if (!buf || size == 0) return buf;
  if (!err) { snprintf(buf, size, "unknown error"); return buf; }
  const char *msg = err->message[0] ? err->message : elfm_status_str(err->code);
  if (err->file[0] && err->line > 0)
    snprintf(buf, size, "%s:%" PRId64 ": %s", err->file, err->line, msg);
  else if (err->file[0] && err->offset >= 0)
    snprintf(buf, size, "%s: byte %" PRId64 ": %s", err->file, err->offset, msg);
  else if (err->file[0])
    snprintf(buf, size, "%s: %s", err->file, msg);
  else
    snprintf(buf, size, "%s", msg);
  return buf;
}
