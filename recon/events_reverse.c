/* events_reverse.c — a recording played backwards (elfm_events_reverse).
 *
 * Why: a one-way z sweep's focus, found where the bead's images are
 * strongest, leans towards the way the bead went (up to 1.9 um on the 5 x
 * 5 array, 3.6 on 3 x 3); played backwards, the bead goes the other way
 * through the same focus and its focus leans the other way, so `calib
 * refine --sweep` takes the mean of the two (docs/recon.md "A one-way
 * sweep read both ways").
 *
 * Backwards, a pixel that brightened dims: each event keeps its pixel and
 * changes polarity, and its time is mirrored within the span of the events
 * kept, so the reversed file covers the same microseconds.
 *
 * Memory does not grow with the recording: the events go forwards into an
 * unnamed temporary file of fixed-size records, which is then read back
 * block by block from its end.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "elfm_events.h"

typedef struct rev_record {
  int64_t t_us;
  uint16_t x, y;
  uint8_t p;
  uint8_t pad[3];
} rev_record;

#define REV_BLOCK 65536

/* The forward pass: the events in [from_us, to_us) into tmp; their count,
 * first and last times, and the largest x and y seen. */
static elfm_status rev_collect(elfm_reader *r, int64_t from_us, int64_t to_us, FILE *tmp, rev_record *buf,
                               elfm_event_chunk *ch, int64_t *n, int64_t *t_first, int64_t *t_last, int *max_x,
                               int *max_y, elfm_error *err)
{
  elfm_status st = from_us > INT64_MIN ? elfm_reader_seek_us(r, from_us, err) : ELFM_OK;
  int done = 0;
  while (st == ELFM_OK && !done) {
    st = elfm_reader_read(r, ch, err);
    if (st != ELFM_OK || (ch->n == 0 && ch->n_trig == 0)) break;
    size_t k = 0;
    for (size_t i = 0; i < ch->n; i++) {
      if (ch->t_us[i] < from_us) continue;
      if (ch->t_us[i] >= to_us) {
        done = 1; /* times never decrease: nothing later is kept */
        break;
      }
      buf[k] = (rev_record){ch->t_us[i], ch->x[i], ch->y[i], ch->p[i], {0, 0, 0}};
      if (ch->x[i] > *max_x) *max_x = ch->x[i];
      if (ch->y[i] > *max_y) *max_y = ch->y[i];
      if (*n == 0) *t_first = ch->t_us[i];
      *t_last = ch->t_us[i];
      (*n)++;
      k++;
    }
    if (k && fwrite(buf, sizeof *buf, k, tmp) != k)
      st = elfm_error_set(err, ELFM_ERR_IO, NULL, -1, "reversing events: temporary file: %s", strerror(errno));
  }
  return st;
}

/* The backward pass: tmp's n records, last first, mirrored, into w. */
static elfm_status rev_write(FILE *tmp, int64_t n, int64_t t_first, int64_t t_last, rev_record *buf,
                             elfm_event_chunk *ch, elfm_writer *w, elfm_error *err)
{
  for (int64_t end = n; end > 0;) {
    const int64_t k = end < REV_BLOCK ? end : REV_BLOCK;
    if (fseeko(tmp, (off_t)((end - k) * (int64_t)sizeof *buf), SEEK_SET) != 0 ||
        fread(buf, sizeof *buf, (size_t)k, tmp) != (size_t)k)
      return elfm_error_set(err, ELFM_ERR_IO, NULL, -1, "reversing events: temporary file: %s",
                            ferror(tmp) ? strerror(errno) : "short read");
    ch->n = 0;
    ch->n_trig = 0;
    for (int64_t i = k - 1; i >= 0; i--) {
      const rev_record *e = &buf[i];
      ch->t_us[ch->n] = t_first + t_last - e->t_us;
      ch->x[ch->n] = e->x;
      ch->y[ch->n] = e->y;
      ch->p[ch->n] = (uint8_t)!e->p;
      ch->n++;
    }
    const elfm_status st = elfm_writer_write(w, ch, err);
    if (st != ELFM_OK) return st;
    end -= k;
  }
  return ELFM_OK;
}

elfm_status elfm_events_reverse(const char *in, const elfm_reader_options *ropt, int64_t from_us, int64_t to_us,
                                const char *out, int64_t *n_events, elfm_error *err)
{
  if (n_events) *n_events = 0;
  if (!in || !out) return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "reversing events: no file given");
  if (to_us <= from_us)
    return elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "reversing events: an empty span of time");
  elfm_reader *r = NULL;
  elfm_status st = elfm_reader_open(in, ropt, &r, err);
  if (st != ELFM_OK) return st;
  elfm_event_chunk *ch = elfm_chunk_create(REV_BLOCK, err);
  rev_record *buf = malloc(REV_BLOCK * sizeof *buf);
  FILE *tmp = tmpfile();
  if (!ch || !buf || !tmp) {
    if (ch && buf) st = elfm_error_set(err, ELFM_ERR_IO, NULL, -1, "reversing events: no temporary file: %s",
                                       strerror(errno));
    else if (ch) st = elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "reversing events: out of memory");
    else st = ELFM_ERR_NOMEM; /* elfm_chunk_create said so */
  }
  int64_t n = 0, t_first = 0, t_last = 0;
  int max_x = -1, max_y = -1;
  if (st == ELFM_OK) st = rev_collect(r, from_us, to_us, tmp, buf, ch, &n, &t_first, &t_last, &max_x, &max_y, err);
  /* the file's own geometry, else the smallest that holds every event */
  int width = elfm_reader_width(r), height = elfm_reader_height(r);
  if (width <= 0 || height <= 0) {
    width = max_x + 1 > 1 ? max_x + 1 : 1;
    height = max_y + 1 > 1 ? max_y + 1 : 1;
  }
  elfm_reader_close(r);
  elfm_writer *w = NULL;
  if (st == ELFM_OK && fflush(tmp) != 0)
    st = elfm_error_set(err, ELFM_ERR_IO, NULL, -1, "reversing events: temporary file: %s", strerror(errno));
  if (st == ELFM_OK) st = elfm_writer_open(out, ELFM_FMT_EVT3, width, height, &w, err);
  if (st == ELFM_OK) st = rev_write(tmp, n, t_first, t_last, buf, ch, w, err);
  if (w) {
    elfm_error cerr;
    elfm_error_clear(&cerr);
    const elfm_status cs = elfm_writer_close(w, &cerr);
    if (st == ELFM_OK && cs != ELFM_OK) {
      st = cs;
      if (err) *err = cerr;
    }
  }
  if (tmp) fclose(tmp);
  free(buf);
  elfm_chunk_free(ch);
  if (st == ELFM_OK && n_events) *n_events = n;
  return st;
}
