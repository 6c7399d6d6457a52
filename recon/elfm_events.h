/* elfm_events.h — streaming event-file reading and writing.
 *
 * Formats (SPEC §4), detected from the file's header: Prophesee RAW EVT 3.0,
 * EVT 2.0, EVT 2.1, Prophesee DAT (Event2D), and CSV "t_us,x,y,p".
 * Writers: EVT 3.0 and CSV.
 *
 * Memory: a reader holds a fixed-size input buffer; events go into a caller's
 * elfm_event_chunk that is reused from call to call, so memory does not grow
 * with the recording's length. Times are absolute microseconds (int64_t).
 *
 * Ownership: the _create/_open calls allocate; the matching _free/_close frees.
 * Every _free/_close accepts NULL.
 */
#ifndef ELFM_EVENTS_H
#define ELFM_EVENTS_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum elfm_event_format {
  ELFM_FMT_UNKNOWN = 0,
  ELFM_FMT_EVT3,
  ELFM_FMT_EVT2,
  ELFM_FMT_EVT21,
  ELFM_FMT_DAT,
  ELFM_FMT_CSV
} elfm_event_format;

/* An external trigger edge (EVT EXT_TRIGGER word). */
typedef struct elfm_trigger {
  int64_t t_us;
  uint8_t channel; /* trigger channel id */
  uint8_t value;   /* 1 rising, 0 falling */
} elfm_trigger;

/* A chunk of events as a structure of arrays, reused from read to read.
 * Invariants: n <= cap; n_trig <= cap_trig; within one chunk and from one
 * chunk to the next, t_us never decreases (readers of real files keep the
 * sensor's order; a decreasing time in a file is reported, not reordered). */
typedef struct elfm_event_chunk {
  int64_t *t_us;
  uint16_t *x, *y;  /* pixel column and row, < the reader's width/height */
  uint8_t *p;       /* polarity: 1 ON (brighter), 0 OFF */
  size_t n, cap;
  elfm_trigger *trig;
  size_t n_trig, cap_trig;
} elfm_event_chunk;

/* Allocate a chunk able to hold `cap` events (and up to 1024 triggers).
 * Returns NULL (and fills err) when out of memory. Free with elfm_chunk_free. */
elfm_event_chunk *elfm_chunk_create(size_t cap, elfm_error *err);
void elfm_chunk_free(elfm_event_chunk *chunk);

/* Name of a format ("evt3", "evt2", "evt21", "dat", "csv"); "unknown" else. */
const char *elfm_format_name(elfm_event_format fmt);
/* Parse a name as above; ELFM_FMT_UNKNOWN when not recognised. */
elfm_event_format elfm_format_from_name(const char *name);

/* ---- reading ---- */
typedef struct elfm_reader_options {
  int width, height;   /* geometry to use when the file has none (DAT); 0 = unknown */
  /* 0 (default): a time that goes back is a format error naming the byte
   * offset/line. 1: keep the file's order and count the backward steps
   * (elfm_reader_backward_steps), as `eventlfm info` does. */
  int allow_unsorted;
} elfm_reader_options;

typedef struct elfm_reader elfm_reader;

/* Open `path`, read and check its header, detect the format.
 * `opt` may be NULL. On failure *out is NULL and err names file and offset. */
elfm_status elfm_reader_open(const char *path, const elfm_reader_options *opt,
                             elfm_reader **out, elfm_error *err);

/* Decode the next events into `chunk` (its n and n_trig are reset first),
 * at most chunk->cap events. Returns ELFM_OK with chunk->n == 0 and
 * chunk->n_trig == 0 at end of file. On a decoding error the events decoded
 * before it stay in `chunk` and err names file and byte offset (or line). */
elfm_status elfm_reader_read(elfm_reader *r, elfm_event_chunk *chunk, elfm_error *err);

/* Position the reader so that the next read returns the first event with
 * t_us >= t_us (from the beginning of the file if needed). */
elfm_status elfm_reader_seek_us(elfm_reader *r, int64_t t_us, elfm_error *err);

elfm_event_format elfm_reader_format(const elfm_reader *r);
int elfm_reader_width(const elfm_reader *r);   /* 0 when unknown */
int elfm_reader_height(const elfm_reader *r);  /* 0 when unknown */
const char *elfm_reader_path(const elfm_reader *r);
/* How much of the file's events has been decoded, 0..1 (by bytes); -1 when
 * the input has no size (a pipe). For progress lines. */
double elfm_reader_fraction(const elfm_reader *r);
/* Times seen going back so far (only non-zero with allow_unsorted). */
int64_t elfm_reader_backward_steps(const elfm_reader *r);
void elfm_reader_close(elfm_reader *r);

/* ---- writing ---- */
typedef struct elfm_writer elfm_writer;

/* Create `path` (truncating) for events of a width x height sensor.
 * fmt: ELFM_FMT_EVT3 or ELFM_FMT_CSV. */
elfm_status elfm_writer_open(const char *path, elfm_event_format fmt, int width,
                             int height, elfm_writer **out, elfm_error *err);

/* Append a chunk's events and triggers (merged by time). Times must not
 * decrease across calls; coordinates must lie inside the geometry. */
elfm_status elfm_writer_write(elfm_writer *w, const elfm_event_chunk *chunk, elfm_error *err);

/* Flush and close; frees `w` even when the final flush fails. */
elfm_status elfm_writer_close(elfm_writer *w, elfm_error *err);

/* ---- playing backwards ---- */

/* Write the events of `in` with from_us <= t_us < to_us to `out` (EVT 3.0)
 * as the sensor would have seen the scene played backwards: last event
 * first, each at t_first + t_last - t_us (the same span of time) and of the
 * other polarity (a pixel that brightened dims). Triggers are left out.
 * The geometry is the file's, else the smallest holding every event.
 * Memory does not grow with the span: the events pass through an unnamed
 * temporary file. *n_events (may be NULL) = the events written. A reading
 * error names `in` and its offset; `out` then holds nothing useful and is
 * the caller's to remove. Why: recon/events_reverse.c. */
elfm_status elfm_events_reverse(const char *in, const elfm_reader_options *ropt, int64_t from_us, int64_t to_us,
                                const char *out, int64_t *n_events, elfm_error *err);

#ifdef __cplusplus
}
#endif
#endif
