/* writer_csv.c — CSV events "t_us,x,y,p" (SPEC §4). Triggers have no
 * place in this format and are not written. */
#include <string.h>

#include "events_internal.h"
#include "fmt_num.h"

elfm_status elfm_csv_write_header(elfm_writer *w, elfm_error *err)
{
  (void)err;
  memcpy(w->buf, "t_us,x,y,p\n", 11);
  w->len = 11;
  return ELFM_OK;
}

elfm_status elfm_csv_write_events(elfm_writer *w, const elfm_event_chunk *c, elfm_error *err)
{
  for (size_t i = 0; i < c->n; i++) {
    /* 19 + 1 + 5 + 1 + 5 + 1 + 1 + 1 bytes at most. */
    if (elfm_writer_reserve(w, 40, err)) return ELFM_ERR_IO;
    char *o = (char *)w->buf + w->len;
    size_t k = elfm_fmt_u64(o, (uint64_t)c->t_us[i]);
    o[k++] = ',';
    k += elfm_fmt_u64(o + k, c->x[i]);
    o[k++] = ',';
    k += elfm_fmt_u64(o + k, c->y[i]);
    o[k++] = ',';
    o[k++] = (char)('0' + c->p[i]);
    o[k++] = '\n';
    w->len += k;
  }
  if (c->n) w->t_last = c->t_us[c->n - 1];
  for (size_t i = 0; i < c->n_trig; i++)
    if (c->trig[i].t_us > w->t_last) w->t_last = c->trig[i].t_us;
  return ELFM_OK;
}
