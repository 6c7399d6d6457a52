/* events_internal.h — private to recon/: the reader and writer objects and
 * the per-format decoder/encoder entry points behind elfm_events.h.
 *
 * Reader shape: one buffered input (ELFM_READ_BUF_BYTES, refilled with
 * fread) shared by all formats; a format-specific decoder turns the bytes in
 * buf[pos..len) into events. A decoder stops when (a) fewer bytes than one
 * whole word/line are left (it sets need_more), (b) the chunk has less room
 * than the most events one word can yield (max_per_word), or (c) the chunk's
 * trigger array is full. The generic loop in reader.c refills, and when a
 * chunk has a little room left but less than max_per_word it decodes one
 * word into the small `pend` chunk and copies out what fits, so any chunk
 * capacity >= 1 works and nothing is lost.
 */
#ifndef ELFM_EVENTS_INTERNAL_H
#define ELFM_EVENTS_INTERNAL_H

#include <stdint.h>
#include <stdio.h>

#include "elfm_events.h"

/* 4 MiB: big enough that fread's per-call cost is invisible next to the
 * decode (a refill every ~2 M EVT3 words), small enough to stay in L2/L3 of
 * a desktop CPU with the chunk arrays beside it. Also the header limit:
 * a header must end within the first buffer. */
#define ELFM_READ_BUF_BYTES ((size_t)4 << 20)
/* The most chunk slots one input word may need: an EVT 2.1 word has a
 * 32-bit valid mask; an EVT3 VECT_12 gives 12 events but the decoder
 * writes 16 slots (see evt3.c). */
#define ELFM_PEND_CAP 32
/* CSV: longest accepted line. "t_us,x,y,p" with a 19-digit time is < 40
 * bytes; 1024 leaves room for trailing spaces and extra columns while a
 * binary file misread as text fails fast instead of growing memory. */
#define ELFM_CSV_MAX_LINE 1024

/* EVT3 decoder state (all times absolute microseconds). The last word of
 * each type is kept whole in regs[type] (ADDR_Y: y, VECT_BASE_X: base x
 * and polarity, TIME_LOW: low time bits), which lets the decoder update
 * its state with one store instead of a branch per word type. Vectors
 * add their advance (12 or 8 columns) to regs[VECT_BASE_X] above bit 16,
 * so a new VECT_BASE_X word restarts it by being stored. */
typedef struct elfm_evt3_state {
  uint32_t regs[16];  /* last word of each type; 0 = none yet */
  int64_t t_high;     /* loops << 24 | TIME_HIGH << 12 */
  int64_t loops;      /* 2^24 us loops counted so far */
  int64_t t_emit;     /* time of the last event stored (order check) */
  uint32_t prev_th;   /* last TIME_HIGH value (12 bits) */
  int seen_th;        /* words before the first TIME_HIGH are dropped */
  int seen_y;         /* events before the first ADDR_Y are dropped */
} elfm_evt3_state;

/* EVT 2.0 / 2.1 decoder state. */
typedef struct elfm_evt2_state {
  int64_t t_high;     /* (loops << 28 | TIME_HIGH) << 6 */
  int64_t loops;
  uint32_t prev_th;   /* last 28-bit TIME_HIGH */
  int seen_th;
  int64_t t_last;     /* last event time, for the order check */
} elfm_evt2_state;

/* DAT decoder state: 32-bit times are unwrapped. */
typedef struct elfm_dat_state {
  int64_t wrap;       /* multiple of 2^32 added to the stored time */
  int64_t t_last;
  int started;
} elfm_dat_state;

/* CSV decoder state. */
typedef struct elfm_csv_state {
  int64_t line;       /* 1-based number of the next line to parse */
  int64_t t_last;
  int started;
} elfm_csv_state;

typedef struct elfm_reader elfm_reader;
typedef elfm_status (*elfm_decode_fn)(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);

struct elfm_reader {
  char *path;               /* owned copy */
  FILE *f;
  elfm_event_format fmt;
  int width, height;        /* 0 = unknown */
  int evt21_legacy;         /* EVT 2.1 with 32-bit halves swapped (IMX636) */
  int64_t data_offset;      /* first byte after the header (and DAT's type/size) */
  int64_t file_bytes;       /* the file's size; -1 when it has none (a pipe) */
  int64_t header_lines;     /* CSV: lines before the first event line */

  uint8_t *buf;             /* buf_cap bytes */
  size_t buf_cap;           /* ELFM_READ_BUF_BYTES, less for small files */
  size_t len, pos;          /* valid bytes, next byte to decode */
  int64_t buf_off;          /* file offset of buf[0] */
  int eof;                  /* no more bytes after buf[len) */
  int need_more;            /* decoder could not finish a word/line */
  size_t word_bytes;        /* 2, 4, 8, 8, 1 (CSV: lines) */
  size_t max_per_word;
  elfm_decode_fn decode;

  /* Limits used by the checks: width/height when known, else the
   * format's coordinate range. */
  uint32_t x_lim, y_lim;

  union {
    elfm_evt3_state evt3;
    elfm_evt2_state evt2;
    elfm_dat_state dat;
    elfm_csv_state csv;
  } st;

  elfm_event_chunk pend;    /* overflow of one word (see top) */
  size_t pend_pos;          /* next pending event to hand out */
  size_t pend_trig_pos;

  int64_t skip_before_us;   /* seek: drop events earlier than this */
  int skipping;

  int allow_unsorted;       /* see elfm_reader_options */
  int64_t backward_steps;   /* times that went back (allow_unsorted) */
  int64_t t_last_out;       /* time of the last event handed out */

  int failed;               /* sticky: a decoding error ends the stream */
  elfm_error fail_err;
};

/* Decoders (one file each). They read r->buf[r->pos..r->len) and advance
 * r->pos past whole words only. */
elfm_status elfm_evt3_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);
elfm_status elfm_evt2_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);
elfm_status elfm_evt21_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);
elfm_status elfm_dat_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);
elfm_status elfm_csv_decode(elfm_reader *r, elfm_event_chunk *c, elfm_error *err);

/* Little-endian loads that compile to one move on x86/ARM. */
static inline uint16_t elfm_le16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t elfm_le32(const uint8_t *p)
{
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* The words EVT 2.0 and EVT 2.1 share (the 32-bit word, or a 64-bit word's
 * event half). TIME_HIGH (type 0x8) holds t[33:6] in 27..0; one far below
 * the previous one (by half the 28-bit range or more) starts a new loop, as
 * for EVT3. Before the first, the order check starts from that time. */
static inline void elfm_evt2_time_high(elfm_evt2_state *s, uint32_t w)
{
  const uint32_t th = w & 0x0FFFFFFF;
  if (s->seen_th && th + (1u << 27) <= s->prev_th) s->loops++;
  else if (!s->seen_th) s->t_last = ((s->loops << 28) | th) << 6;
  s->prev_th = th;
  s->t_high = ((s->loops << 28) | (int64_t)th) << 6;
  s->seen_th = 1;
}

/* EXT_TRIGGER (type 0xA): t[5:0] in 27..22, channel in 12..8, value bit 0.
 * Kept when the chunk takes triggers and a TIME_HIGH came before; returns
 * 0 when the chunk's triggers are full (the word is then read again into
 * the next chunk), else 1. */
static inline int elfm_evt2_trigger(const elfm_evt2_state *s, elfm_event_chunk *c, uint32_t w)
{
  if (!s->seen_th || !c->cap_trig) return 1;
  if (c->n_trig >= c->cap_trig) return 0;
  elfm_trigger *tr = &c->trig[c->n_trig++];
  tr->t_us = s->t_high | ((w >> 22) & 63);
  tr->channel = (uint8_t)((w >> 8) & 0x1F);
  tr->value = (uint8_t)(w & 1);
  return 1;
}

/* Writer: a buffered output plus a format encoder. */
typedef struct elfm_writer_evt3_state {
  int64_t th_abs;      /* absolute TIME_HIGH (t >> 12) last written, -1 none */
  int64_t low;         /* TIME_LOW last written (t & 0xFFF), -1 after TIME_HIGH */
  int64_t y;           /* ADDR_Y last written, -1 none */
} elfm_writer_evt3_state;

struct elfm_writer {
  char *path;
  FILE *f;
  elfm_event_format fmt;
  int width, height;
  uint8_t *buf;
  size_t len, cap;
  int64_t t_last;       /* last time written (events and triggers), -1 none */
  int64_t bytes_written;
  elfm_writer_evt3_state evt3;
  int failed;
};

/* Make room for `need` more bytes in w->buf (flushing to the file). */
elfm_status elfm_writer_reserve(elfm_writer *w, size_t need, elfm_error *err);
elfm_status elfm_writer_flush(elfm_writer *w, elfm_error *err);
elfm_status elfm_evt3_write_header(elfm_writer *w, elfm_error *err);
elfm_status elfm_evt3_write_events(elfm_writer *w, const elfm_event_chunk *c, elfm_error *err);
elfm_status elfm_csv_write_header(elfm_writer *w, elfm_error *err);
elfm_status elfm_csv_write_events(elfm_writer *w, const elfm_event_chunk *c, elfm_error *err);

#endif
