/* chunk.c — the event chunk (structure of arrays) and format names. */
#include <stdlib.h>
#include <string.h>

#include "elfm_events.h"

/* 1024 triggers per chunk: trigger edges come at most at a few kHz, so a
 * chunk of even 1 s of events rarely holds more; a reader stops a chunk
 * early when the trigger array fills, so nothing is lost either way. */
#define ELFM_CHUNK_TRIG_CAP 1024

elfm_event_chunk *elfm_chunk_create(size_t cap, elfm_error *err)
{
  if (cap == 0 || cap > ((size_t)1 << 40)) {
    elfm_error_set(err, ELFM_ERR_INVALID, NULL, -1, "chunk capacity %zu is out of range", cap);
    return NULL;
  }
  elfm_event_chunk *c = calloc(1, sizeof *c);
  if (!c) goto nomem;
  c->t_us = malloc(cap * sizeof *c->t_us);
  c->x = malloc(cap * sizeof *c->x);
  c->y = malloc(cap * sizeof *c->y);
  c->p = malloc(cap);
  c->trig = malloc(ELFM_CHUNK_TRIG_CAP * sizeof *c->trig);
  if (!c->t_us || !c->x || !c->y || !c->p || !c->trig) goto nomem;
  c->cap = cap;
  c->cap_trig = ELFM_CHUNK_TRIG_CAP;
  return c;
nomem:
  elfm_chunk_free(c);
  elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory for a chunk of %zu events", cap);
  return NULL;
}

void elfm_chunk_free(elfm_event_chunk *c)
{
  if (!c) return;
  free(c->t_us);
  free(c->x);
  free(c->y);
  free(c->p);
  free(c->trig);
  free(c);
}

static const char *const format_names[] = {"unknown", "evt3", "evt2", "evt21", "dat", "csv"};

const char *elfm_format_name(elfm_event_format fmt)
{
  if ((int)fmt < 0 || (size_t)fmt >= sizeof format_names / sizeof format_names[0]) return "unknown";
  return format_names[fmt];
}

elfm_event_format elfm_format_from_name(const char *name)
{
  if (!name) return ELFM_FMT_UNKNOWN;
  for (size_t i = 1; i < sizeof format_names / sizeof format_names[0]; i++)
    if (!strcmp(name, format_names[i])) return (elfm_event_format)i;
  return ELFM_FMT_UNKNOWN;
}
