/* csv_events.c — CSV events "t_us,x,y,p" (SPEC §4), one event per line.
 *
 * Strict: every line must be four non-negative integers (t_us, x, y and
 * p in {0,1}); further columns are ignored, a trailing '\r' is accepted,
 * blank lines are skipped. Times must not decrease. Errors name the line.
 */
#include "events_internal.h"

#include <string.h>

/* Parse an unsigned decimal of at most `maxdig` digits; returns the
 * pointer after it, or NULL. */
static const char *parse_u(const char *s, const char *e, int maxdig, uint64_t *out)
{
  uint64_t v = 0;
  int d = 0;
  while (s < e && *s >= '0' && *s <= '9') {
    if (++d > maxdig) return NULL;
    v = v * 10 + (uint64_t)(*s - '0');
    s++;
  }
  if (!d) return NULL;
  *out = v;
  return s;
}

elfm_status elfm_csv_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_csv_state s = r->st.csv;
  const char *b = (const char *)r->buf;
  size_t pos = r->pos;
  size_t n = c->n;
  elfm_status st = ELFM_OK;

  r->need_more = 0;
  while (n < c->cap && pos < r->len) {
    size_t avail = r->len - pos;
    size_t look = avail < ELFM_CSV_MAX_LINE + 1 ? avail : ELFM_CSV_MAX_LINE + 1;
    const char *ls = b + pos;
    const char *nl = memchr(ls, '\n', look);
    const char *le;
    size_t next;
    if (nl) {
      le = nl;
      next = pos + (size_t)(nl - ls) + 1;
    } else if (avail > ELFM_CSV_MAX_LINE) {
      st = elfm_error_set_line(err, ELFM_ERR_FORMAT, r->path, s.line,
                               "line longer than %d bytes", ELFM_CSV_MAX_LINE);
      goto out;
    } else if (!r->eof) {
      r->need_more = 1;
      break;
    } else {
      le = b + r->len; /* last line without a newline */
      next = r->len;
    }
    if (le > ls && le[-1] == '\r') le--;
    if (le == ls) { /* blank line */
      s.line++;
      pos = next;
      continue;
    }
    uint64_t t, x, y, p;
    const char *q = parse_u(ls, le, 18, &t);
    if (q && q < le && *q == ',') q = parse_u(q + 1, le, 5, &x); else q = NULL;
    if (q && q < le && *q == ',') q = parse_u(q + 1, le, 5, &y); else q = NULL;
    if (q && q < le && *q == ',') q = parse_u(q + 1, le, 1, &p); else q = NULL;
    if (!q || (q < le && *q != ',' && *q != ' ') || p > 1) {
      int shown = (int)(le - ls > 60 ? 60 : le - ls);
      st = elfm_error_set_line(err, ELFM_ERR_FORMAT, r->path, s.line,
                               "expected 't_us,x,y,p' (non-negative integers, p 0 or 1), got '%.*s'",
                               shown, ls);
      goto out;
    }
    if (x >= r->x_lim || y >= r->y_lim) {
      st = elfm_error_set_line(err, ELFM_ERR_RANGE, r->path, s.line,
                               "event at x=%llu y=%llu outside the sensor %ux%u",
                               (unsigned long long)x, (unsigned long long)y, r->x_lim, r->y_lim);
      goto out;
    }
    if (s.started && (int64_t)t < s.t_last) {
      if (!r->allow_unsorted) {
        st = elfm_error_set_line(err, ELFM_ERR_FORMAT, r->path, s.line,
                                 "rows not sorted by time: %llu after %lld",
                                 (unsigned long long)t, (long long)s.t_last);
        goto out;
      }
      r->backward_steps++;
    }
    s.started = 1;
    s.t_last = (int64_t)t;
    c->t_us[n] = (int64_t)t;
    c->x[n] = (uint16_t)x;
    c->y[n] = (uint16_t)y;
    c->p[n] = (uint8_t)p;
    n++;
    s.line++;
    pos = next;
  }
out:
  r->pos = pos;
  c->n = n;
  r->st.csv = s;
  return st;
}
