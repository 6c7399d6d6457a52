/* reader.c — opening an event file: header parsing, format detection,
 * geometry, and the generic buffered read loop that drives the decoders
 * (evt3.c, evt2.c, evt21.c, dat.c, csv_events.c). See events_internal.h. */
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "events_internal.h"

/* ---- header parsing ---- */

typedef struct header_info {
  elfm_event_format fmt;      /* from "% evt" / "% format" / DAT marker */
  elfm_event_format plugin_fmt; /* fallback from the plugin name */
  int width, height;          /* from "% format" or "% geometry" or DAT */
  int plugin_width, plugin_height;
  int legacy21;
} header_info;

/* Parse a positive decimal of at most 9 digits at s (so it cannot
 * overflow); returns the number of characters used, 0 if none. */
static size_t parse_dim(const char *s, int *out)
{
  size_t i = 0;
  long v = 0;
  while (s[i] >= '0' && s[i] <= '9') {
    if (i >= 9) return 0;
    v = v * 10 + (s[i] - '0');
    i++;
  }
  if (i == 0) return 0;
  *out = (int)v;
  return i;
}

/* Largest width/height each format can address: EVT x/y are 11 bits,
 * DAT x/y 14 bits, CSV x/y are stored as uint16. */
static int format_max_dim(elfm_event_format fmt)
{
  switch (fmt) {
  case ELFM_FMT_EVT3:
  case ELFM_FMT_EVT2:
  case ELFM_FMT_EVT21: return 2048;
  case ELFM_FMT_DAT: return 16384;
  default: return 65536;
  }
}

static int starts_with(const char *s, const char *prefix)
{
  return strncmp(s, prefix, strlen(prefix)) == 0;
}

/* One "% ..." header line (NUL-terminated, without the newline). */
static elfm_status parse_header_line(const char *path, int64_t off, const char *line,
                                     header_info *h, int *end, elfm_error *err)
{
  const char *s = line + 1;
  while (*s == ' ' || *s == '\t') s++;
  if (!strcmp(s, "end")) {
    *end = 1;
    return ELFM_OK;
  }
  if (starts_with(s, "evt ")) {
    const char *v = s + 4;
    if (!strcmp(v, "3.0")) h->fmt = ELFM_FMT_EVT3;
    else if (!strcmp(v, "2.0")) h->fmt = ELFM_FMT_EVT2;
    else if (!strcmp(v, "2.1")) { h->fmt = ELFM_FMT_EVT21; h->legacy21 = 1; }
    else
      return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, path, off,
                            "unsupported event format 'evt %s' (supported: 2.0, 2.1, 3.0)", v);
    return ELFM_OK;
  }
  if (starts_with(s, "format ")) {
    /* "% format EVT3;height=720;width=1280" (OpenEB >= 4). */
    const char *v = s + 7;
    size_t nlen = strcspn(v, ";");
    if (nlen == 4 && !strncmp(v, "EVT3", 4)) h->fmt = ELFM_FMT_EVT3;
    else if (nlen == 4 && !strncmp(v, "EVT2", 4)) h->fmt = ELFM_FMT_EVT2;
    else if (nlen == 5 && !strncmp(v, "EVT21", 5)) h->fmt = ELFM_FMT_EVT21;
    else
      return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, path, off,
                            "unsupported event format '%.*s' (supported: EVT2, EVT21, EVT3)",
                            (int)(nlen > 40 ? 40 : nlen), v);
    const char *kv = v + nlen;
    while (*kv == ';') {
      kv++;
      int val;
      if (starts_with(kv, "width=") || starts_with(kv, "height=")) {
        int is_w = kv[0] == 'w';
        const char *num = kv + (is_w ? 6 : 7);
        size_t used = parse_dim(num, &val);
        if (!used || (num[used] != ';' && num[used] != '\0'))
          return elfm_error_set(err, ELFM_ERR_FORMAT, path, off,
                                "bad %s in the format line", is_w ? "width" : "height");
        if (is_w) h->width = val;
        else h->height = val;
      } else if (starts_with(kv, "endianness=legacy")) {
        h->legacy21 = 1;
      }
      kv += strcspn(kv, ";");
    }
    return ELFM_OK;
  }
  if (starts_with(s, "geometry ")) {
    const char *v = s + 9;
    int w = 0, hh = 0;
    size_t a = parse_dim(v, &w);
    size_t b = a && v[a] == 'x' ? parse_dim(v + a + 1, &hh) : 0;
    if (!a || !b || v[a + 1 + b] != '\0')
      return elfm_error_set(err, ELFM_ERR_FORMAT, path, off,
                            "bad geometry line '%.60s' (expected WIDTHxHEIGHT, numbers below 10^9)", v);
    h->width = w;
    h->height = hh;
    return ELFM_OK;
  }
  if (starts_with(s, "plugin_name ")) {
    /* Old files name only the camera plugin; OpenEB maps Gen4.x (IMX636
     * family) to 1280x720 EVT3 and Gen3 to 640x480 EVT2. */
    const char *v = s + 12;
    if (strstr(v, "gen41") || strstr(v, "gen4") || strstr(v, "imx636")) {
      h->plugin_width = 1280;
      h->plugin_height = 720;
      h->plugin_fmt = ELFM_FMT_EVT3;
    } else if (strstr(v, "gen3")) {
      h->plugin_width = 640;
      h->plugin_height = 480;
      h->plugin_fmt = ELFM_FMT_EVT2;
    }
    return ELFM_OK;
  }
  /* DAT: "% Data file containing Event2D events." (or the old mangled
   * C++ name "N9Chronocam7Event2dE"), then "% Width N" / "% Height N". */
  if ((strstr(s, "Event2D") || strstr(s, "Event2dE")) && h->fmt == ELFM_FMT_UNKNOWN) {
    h->fmt = ELFM_FMT_DAT; /* an explicit "% evt"/"% format" line wins */
    return ELFM_OK;
  }
  if (starts_with(s, "Width ") || starts_with(s, "Height ")) {
    int is_w = s[0] == 'W';
    int val;
    const char *num = s + (is_w ? 6 : 7);
    size_t used = parse_dim(num, &val);
    if (!used || num[used] != '\0')
      return elfm_error_set(err, ELFM_ERR_FORMAT, path, off, "bad %s line", is_w ? "Width" : "Height");
    if (is_w) h->width = val;
    else h->height = val;
  }
  return ELFM_OK;
}

/* Read the first buffer of the file. */
static elfm_status refill(elfm_reader *r, elfm_error *err)
{
  size_t left = r->len - r->pos;
  if (left && r->pos) memmove(r->buf, r->buf + r->pos, left);
  r->buf_off += (int64_t)r->pos;
  r->len = left;
  r->pos = 0;
  r->need_more = 0;
  size_t want = r->buf_cap - left;
  size_t got = fread(r->buf + left, 1, want, r->f);
  r->len += got;
  if (got < want) {
    if (ferror(r->f))
      return elfm_error_set(err, ELFM_ERR_IO, r->path, r->buf_off + (int64_t)r->len,
                            "read failed: %s", strerror(errno));
    r->eof = 1;
  }
  return ELFM_OK;
}

static void reset_decoder(elfm_reader *r)
{
  memset(&r->st, 0, sizeof r->st);
  if (r->fmt == ELFM_FMT_CSV) r->st.csv.line = r->header_lines + 1; /* union member */
  r->pend.n = r->pend.n_trig = 0;
  r->pend_pos = r->pend_trig_pos = 0;
  r->failed = 0;
  r->t_last_out = INT64_MIN;
  r->backward_steps = 0;
}

/* Parse the header in the first buffer and set up the decoder. */
static elfm_status parse_header(elfm_reader *r, const elfm_reader_options *opt, elfm_error *err)
{
  header_info h;
  memset(&h, 0, sizeof h);
  const char *path = r->path;
  if (r->len == 0) return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0, "empty file");

  size_t pos = 0;
  int64_t lines = 0;
  if (r->buf[0] == '%') {
    int end = 0;
    char line[ELFM_CSV_MAX_LINE + 1];
    while (!end && pos < r->len && r->buf[pos] == '%') {
      const uint8_t *nl = memchr(r->buf + pos, '\n', r->len - pos);
      if (!nl) {
        if (!r->eof)
          return elfm_error_set(err, ELFM_ERR_FORMAT, path, (int64_t)pos,
                                "header does not end within the first %zu bytes",
                                r->buf_cap);
        return elfm_error_set(err, ELFM_ERR_FORMAT, path, (int64_t)pos,
                              "file ends inside a header line (truncated)");
      }
      size_t llen = (size_t)(nl - (r->buf + pos));
      if (llen > ELFM_CSV_MAX_LINE)
        return elfm_error_set(err, ELFM_ERR_FORMAT, path, (int64_t)pos,
                              "header line of %zu bytes (limit %d)", llen, ELFM_CSV_MAX_LINE);
      memcpy(line, r->buf + pos, llen);
      if (llen && line[llen - 1] == '\r') llen--;
      line[llen] = '\0';
      elfm_status st = parse_header_line(path, (int64_t)pos, line, &h, &end, err);
      if (st != ELFM_OK) return st;
      pos = (size_t)(nl - r->buf) + 1;
      lines++;
    }
    if (h.fmt == ELFM_FMT_UNKNOWN) h.fmt = h.plugin_fmt;
    if (h.fmt == ELFM_FMT_UNKNOWN)
      return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0,
                            "header names no event format ('%% evt', '%% format' or a DAT "
                            "'Event2D' line)");
    if (h.fmt == ELFM_FMT_DAT) {
      /* Two bytes after the DAT header: event type and event size. */
      if (r->len - pos < 2)
        return elfm_error_set(err, ELFM_ERR_FORMAT, path, (int64_t)pos,
                              "DAT file ends before its event type/size bytes");
      uint8_t type = r->buf[pos], size = r->buf[pos + 1];
      if (size != 8)
        return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, path, (int64_t)pos + 1,
                              "DAT event size %u (only 8-byte Event2D records are supported)",
                              size);
      /* 0: Event2D (CD) as written by Prophesee tools; 12 (0x0C): CD in
       * newer Metavision DAT files. Others (IMU, triggers) differ. */
      if (type != 0 && type != 12)
        return elfm_error_set(err, ELFM_ERR_UNSUPPORTED, path, (int64_t)pos,
                              "DAT event type %u (only CD events, type 0 or 12)", type);
      pos += 2;
    }
  } else if (r->len >= 10 && !memcmp(r->buf, "t_us,x,y,p", 10) &&
             (r->len == 10 || r->buf[10] == '\n' || r->buf[10] == '\r' || r->buf[10] == ',')) {
    h.fmt = ELFM_FMT_CSV;
    const uint8_t *nl = memchr(r->buf, '\n', r->len);
    if (!nl && !r->eof)
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, path, 1, "CSV header line too long");
    pos = nl ? (size_t)(nl - r->buf) + 1 : r->len;
    lines = 1;
  } else {
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0,
                          "not an event file: no '%%' header (Prophesee RAW/DAT) and no "
                          "'t_us,x,y,p' CSV header");
  }

  int w = h.width, hh = h.height;
  if (!w && !hh) {
    w = h.plugin_width;
    hh = h.plugin_height;
  }
  if (!w && !hh && opt) {
    w = opt->width;
    hh = opt->height;
  }
  int maxd = format_max_dim(h.fmt);
  if (w < 0 || hh < 0 || w > maxd || hh > maxd || (!w) != (!hh))
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, 0,
                          "geometry %dx%d is outside what %s can address (1..%d)", w, hh,
                          elfm_format_name(h.fmt), maxd);

  r->fmt = h.fmt;
  r->width = w;
  r->height = hh;
  r->x_lim = (uint32_t)(w ? w : maxd);
  r->y_lim = (uint32_t)(hh ? hh : maxd);
  r->evt21_legacy = h.legacy21;
  r->data_offset = (int64_t)pos;
  r->header_lines = lines;
  r->pos = pos;
  switch (h.fmt) {
  case ELFM_FMT_EVT3: r->decode = elfm_evt3_decode; r->word_bytes = 2; r->max_per_word = 16; break;
  case ELFM_FMT_EVT2: r->decode = elfm_evt2_decode; r->word_bytes = 4; r->max_per_word = 1; break;
  case ELFM_FMT_EVT21: r->decode = elfm_evt21_decode; r->word_bytes = 8; r->max_per_word = 32; break;
  case ELFM_FMT_DAT: r->decode = elfm_dat_decode; r->word_bytes = 8; r->max_per_word = 1; break;
  default: r->decode = elfm_csv_decode; r->word_bytes = 1; r->max_per_word = 1; break;
  }
  reset_decoder(r);
  return ELFM_OK;
}

elfm_status elfm_reader_open(const char *path, const elfm_reader_options *opt,
                             elfm_reader **out, elfm_error *err)
{
  if (!out) return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "no output pointer");
  *out = NULL;
  if (!path) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no path");
  if (opt && (opt->width < 0 || opt->height < 0 || opt->width > 65536 || opt->height > 65536))
    return elfm_error_set(err, ELFM_ERR_INVALID, path, -1, "geometry option %dx%d out of range",
                          opt->width, opt->height);
  elfm_reader *r = calloc(1, sizeof *r);
  if (!r) return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  r->path = strdup(path);
  r->f = fopen(path, "rb");
  if (!r->f) {
    elfm_status st = elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot open: %s", strerror(errno));
    elfm_reader_close(r);
    return st;
  }
  /* A small file gets a buffer its size (opening many small files stays
   * cheap); anything else, or what cannot be sized (a pipe), the full
   * buffer. 64 KiB at least so that any plausible header fits. */
  struct stat sb;
  r->buf_cap = ELFM_READ_BUF_BYTES;
  const int sized = fstat(fileno(r->f), &sb) == 0 && S_ISREG(sb.st_mode);
  r->file_bytes = sized ? (int64_t)sb.st_size : -1;
  if (sized && (uint64_t)sb.st_size < ELFM_READ_BUF_BYTES)
    r->buf_cap = (size_t)sb.st_size + 1 < ((size_t)64 << 10) ? ((size_t)64 << 10)
                                                             : (size_t)sb.st_size + 1;
  r->buf = malloc(r->buf_cap);
  r->pend.t_us = malloc(ELFM_PEND_CAP * sizeof *r->pend.t_us);
  r->pend.x = malloc(ELFM_PEND_CAP * sizeof *r->pend.x);
  r->pend.y = malloc(ELFM_PEND_CAP * sizeof *r->pend.y);
  r->pend.p = malloc(ELFM_PEND_CAP);
  r->pend.trig = malloc(ELFM_PEND_CAP * sizeof *r->pend.trig);
  r->pend.cap = ELFM_PEND_CAP;
  r->pend.cap_trig = ELFM_PEND_CAP;
  if (!r->path || !r->buf || !r->pend.t_us || !r->pend.x || !r->pend.y || !r->pend.p ||
      !r->pend.trig) {
    elfm_reader_close(r);
    return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory");
  }
  r->allow_unsorted = opt ? opt->allow_unsorted : 0;
  elfm_status st = refill(r, err);
  if (st == ELFM_OK) st = parse_header(r, opt, err);
  if (st != ELFM_OK) {
    elfm_reader_close(r);
    return st;
  }
  *out = r;
  return ELFM_OK;
}

/* ---- the read loop ---- */

static void drain_pending(elfm_reader *r, elfm_event_chunk *c)
{
  elfm_event_chunk *p = &r->pend;
  while (r->pend_pos < p->n && c->n < c->cap) {
    size_t i = r->pend_pos++, j = c->n++;
    c->t_us[j] = p->t_us[i];
    c->x[j] = p->x[i];
    c->y[j] = p->y[i];
    c->p[j] = p->p[i];
  }
  while (r->pend_trig_pos < p->n_trig && c->n_trig < c->cap_trig)
    c->trig[c->n_trig++] = p->trig[r->pend_trig_pos++];
  if (c->cap_trig == 0) r->pend_trig_pos = p->n_trig; /* caller takes no triggers */
}

static int pending_left(const elfm_reader *r)
{
  return r->pend_pos < r->pend.n || r->pend_trig_pos < r->pend.n_trig;
}

static elfm_status fail(elfm_reader *r, elfm_status st, const elfm_error *err)
{
  r->failed = 1;
  if (err) r->fail_err = *err;
  else elfm_error_set(&r->fail_err, st, r->path, -1, "decoding failed");
  r->fail_err.code = st;
  return st;
}

/* Decode into c until it is full, its triggers are full, or the file ends. */
static elfm_status fill(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  elfm_error local;
  elfm_error *e = err ? err : &local;
  if (r->failed) {
    *e = r->fail_err;
    return r->fail_err.code;
  }
  for (;;) {
    drain_pending(r, c);
    if (c->n >= c->cap || (c->cap_trig && c->n_trig >= c->cap_trig) || pending_left(r))
      return ELFM_OK;
    if (r->need_more || r->pos >= r->len) {
      if (r->eof) {
        if (r->pos < r->len) {
          elfm_error_set(e, ELFM_ERR_FORMAT, r->path, r->buf_off + (int64_t)r->pos,
                         "file ends inside a %zu-byte word (%zu byte%s left): truncated",
                         r->word_bytes, r->len - r->pos, r->len - r->pos == 1 ? "" : "s");
          return fail(r, ELFM_ERR_FORMAT, e);
        }
        return ELFM_OK;
      }
      elfm_status st = refill(r, e);
      if (st != ELFM_OK) return fail(r, st, e);
      continue;
    }
    elfm_event_chunk *dst = c;
    if (c->cap - c->n < r->max_per_word) {
      dst = &r->pend;
      dst->n = dst->n_trig = 0;
      r->pend_pos = r->pend_trig_pos = 0;
    }
    size_t pos0 = r->pos, n0 = dst->n, nt0 = dst->n_trig;
    elfm_status st = r->decode(r, dst, e);
    if (st != ELFM_OK) {
      if (dst != c) drain_pending(r, c);
      return fail(r, st, e);
    }
    if (r->pos == pos0 && !r->need_more && dst->n == n0 && dst->n_trig == nt0)
      return ELFM_OK; /* no progress: the trigger array is full */
  }
}

/* Seek support: drop events (and triggers) before skip_before_us. */
static void apply_skip(elfm_reader *r, elfm_event_chunk *c)
{
  int64_t t0 = r->skip_before_us;
  size_t k = 0;
  while (k < c->n && c->t_us[k] < t0) k++;
  if (k) {
    size_t m = c->n - k;
    memmove(c->t_us, c->t_us + k, m * sizeof *c->t_us);
    memmove(c->x, c->x + k, m * sizeof *c->x);
    memmove(c->y, c->y + k, m * sizeof *c->y);
    memmove(c->p, c->p + k, m);
    c->n = m;
  }
  size_t j = 0;
  for (size_t i = 0; i < c->n_trig; i++)
    if (c->trig[i].t_us >= t0) c->trig[j++] = c->trig[i];
  c->n_trig = j;
  if (c->n > 0) r->skipping = 0;
}

elfm_status elfm_reader_read(elfm_reader *r, elfm_event_chunk *c, elfm_error *err)
{
  if (!r || !c) return elfm_error_set(err, ELFM_ERR_INVALID, r ? r->path : NULL, -1, "no reader or chunk");
  for (;;) {
    c->n = 0;
    c->n_trig = 0;
    elfm_status st = fill(r, c, err);
    if (r->skipping) apply_skip(r, c);
    /* What was handed out (events and triggers): seeking before it must
     * start over. */
    if (c->n && c->t_us[c->n - 1] > r->t_last_out) r->t_last_out = c->t_us[c->n - 1];
    if (c->n_trig && c->trig[c->n_trig - 1].t_us > r->t_last_out)
      r->t_last_out = c->trig[c->n_trig - 1].t_us;
    if (st != ELFM_OK) return st;
    int at_end = r->eof && r->pos >= r->len && !pending_left(r);
    if (c->n > 0 || c->n_trig > 0 || at_end) return ELFM_OK;
  }
}

elfm_status elfm_reader_seek_us(elfm_reader *r, int64_t t_us, elfm_error *err)
{
  if (!r) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "no reader");
  /* Forward seeks from a healthy position just skip; otherwise start over
   * from the first event. */
  if (r->failed || t_us < r->t_last_out) {
    if (fseeko(r->f, (off_t)r->data_offset, SEEK_SET) != 0)
      return elfm_error_set(err, ELFM_ERR_IO, r->path, r->data_offset, "seek failed: %s",
                            strerror(errno));
    clearerr(r->f);
    r->len = r->pos = 0;
    r->buf_off = r->data_offset;
    r->eof = 0;
    r->need_more = 0;
    reset_decoder(r);
  }
  r->skip_before_us = t_us;
  r->skipping = 1;
  return ELFM_OK;
}

elfm_event_format elfm_reader_format(const elfm_reader *r) { return r ? r->fmt : ELFM_FMT_UNKNOWN; }
int elfm_reader_width(const elfm_reader *r) { return r ? r->width : 0; }
int elfm_reader_height(const elfm_reader *r) { return r ? r->height : 0; }
const char *elfm_reader_path(const elfm_reader *r) { return r ? r->path : NULL; }

double elfm_reader_fraction(const elfm_reader *r)
{
  if (!r || r->file_bytes < 0) return -1;
  const double body = (double)(r->file_bytes - r->data_offset);
  if (!(body > 0)) return 1;
  const double f = (double)(r->buf_off + (int64_t)r->pos - r->data_offset) / body;
  return f < 0 ? 0 : f > 1 ? 1 : f;
}
int64_t elfm_reader_backward_steps(const elfm_reader *r) { return r ? r->backward_steps : 0; }

void elfm_reader_close(elfm_reader *r)
{
  if (!r) return;
  if (r->f) fclose(r->f);
  free(r->path);
  free(r->buf);
  free(r->pend.t_us);
  free(r->pend.x);
  free(r->pend.y);
  free(r->pend.p);
  free(r->pend.trig);
  free(r);
}
