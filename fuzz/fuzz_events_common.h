/* fuzz_events_common.h — shared body of the event-decoder fuzz targets.
 *
 * The input becomes a file (the readers take paths): as it is when it
 * starts like a header of the target's format, else behind that format's
 * header, so most inputs reach the decoder and some fuzz the header parser.
 * It is decoded with a 13-event chunk (vectors straddle chunk ends), then
 * once more after a seek into the middle. Any crash, sanitizer report or
 * hang is a bug; errors are fine. */
#ifndef ELFM_FUZZ_EVENTS_COMMON_H
#define ELFM_FUZZ_EVENTS_COMMON_H

#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "elfm_events.h"

static inline void fuzz_events_run(const uint8_t *data, size_t size, const char *header,
                                   size_t hl, const char *tag)
{
  char path[128];
  snprintf(path, sizeof path, "/tmp/elfm_fuzz_%s_%ld.bin", tag, (long)getpid());
  FILE *f = fopen(path, "wb");
  if (!f) return;
  if (size < hl || memcmp(data, header, 2) != 0) fwrite(header, 1, hl, f);
  if (size) fwrite(data, 1, size, f);
  fclose(f);

  elfm_reader_options opt = {640, 480, (int)(size & 1)};
  elfm_reader *r = NULL;
  elfm_error err;
  if (elfm_reader_open(path, &opt, &r, &err) == ELFM_OK) {
    elfm_event_chunk *c = elfm_chunk_create(13, &err);
    int64_t t_mid = -1;
    size_t total = 0;
    for (int pass = 0; pass < 2 && c; pass++) {
      for (;;) {
        elfm_status st = elfm_reader_read(r, c, &err);
        for (size_t i = 0; i < c->n; i++) {
          /* The contract: inside the geometry. */
          if ((elfm_reader_width(r) && c->x[i] >= elfm_reader_width(r)) ||
              (elfm_reader_height(r) && c->y[i] >= elfm_reader_height(r)) || c->p[i] > 1)
            __builtin_trap();
          if (++total == 20) t_mid = c->t_us[i];
        }
        if (st != ELFM_OK || (!c->n && !c->n_trig)) break;
      }
      if (t_mid < 0 || elfm_reader_seek_us(r, t_mid, &err) != ELFM_OK) break;
    }
    elfm_chunk_free(c);
    elfm_reader_close(r);
  }
  unlink(path);
}

#endif
