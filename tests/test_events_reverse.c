/* test_events_reverse.c — a recording played backwards
 * (elfm_events_reverse, recon/events_reverse.c):
 *  - 150,000 random events over 3 s (more than two of its blocks of
 *    65,536), reversed whole: the same count, last event first, each at
 *    t_first + t_last - t with the other polarity and the same pixel, the
 *    file's geometry kept; reversed again, the original to the event;
 *  - a span [from, to): only its events, mirrored within their own span;
 *  - a CSV without a geometry: the smallest holding every event;
 *  - an empty span, and a span with no events in it: a valid empty file;
 *  - bad input: a missing file, a truncated one (the error names it and
 *    its byte offset), an output that cannot be made, from >= to: errors,
 *    never a crash. */
#include "test_events_common.h"

static char dir[256];

static const char *path_of(const char *name, char *p, size_t n)
{
  snprintf(p, n, "%s/%s", dir, name);
  return p;
}

/* Write l's events to path (EVT3, 1280 x 720) with the library's writer. */
static void write_evt3(const char *path, const ev_list *l)
{
  elfm_error err;
  elfm_writer *w = NULL;
  CHECK_OK(elfm_writer_open(path, ELFM_FMT_EVT3, 1280, 720, &w, &err), &err);
  elfm_event_chunk c = {l->t, l->x, l->y, l->p, l->n, l->n, NULL, 0, 0};
  CHECK_OK(elfm_writer_write(w, &c, &err), &err);
  CHECK_OK(elfm_writer_close(w, &err), &err);
}

/* b is a played backwards over [i0, i1): the same pixels, last first,
 * mirrored in time within a's span of those events, polarities swapped */
static int is_reversed(const ev_list *a, size_t i0, size_t i1, const ev_list *b)
{
  if (b->n != i1 - i0) return 0;
  if (i1 == i0) return 1;
  const int64_t t0 = a->t[i0], t1 = a->t[i1 - 1];
  for (size_t k = 0; k < b->n; k++) {
    const size_t i = i1 - 1 - k;
    if (b->t[k] != t0 + t1 - a->t[i] || b->x[k] != a->x[i] || b->y[k] != a->y[i] || b->p[k] != !a->p[i]) {
      fprintf(stderr, "  event %zu: (%" PRId64 ", %d, %d, %d), wanted the mirror of (%" PRId64 ", %d, %d, %d)\n", k,
              b->t[k], b->x[k], b->y[k], b->p[k], a->t[i], a->x[i], a->y[i], a->p[i]);
      return 0;
    }
  }
  return 1;
}

static void test_whole_and_span(void)
{
  char pin[600], pout[600], pback[600];
  ev_list a = {0};
  uint64_t seed = 7;
  int64_t t = 1000000; /* absolute times, as a camera's */
  for (int i = 0; i < 150000; i++) {
    t += (int64_t)(rng_next(&seed) % 40); /* repeated times too */
    ev_push(&a, t, (int)(rng_next(&seed) % 1280), (int)(rng_next(&seed) % 720), (int)(rng_next(&seed) & 1));
  }
  write_evt3(path_of("in.raw", pin, sizeof pin), &a);
  elfm_error err;
  int64_t n = -1;
  CHECK_OK(elfm_events_reverse(pin, NULL, INT64_MIN, INT64_MAX, path_of("rev.raw", pout, sizeof pout), &n, &err),
           &err);
  CHECK_EQ_INT(n, (int64_t)a.n);
  ev_list b = {0};
  CHECK_OK(ev_decode_file(pout, NULL, 4096, &b, &err), &err);
  CHECK_MSG(is_reversed(&a, 0, a.n, &b), "the whole file reversed");
  elfm_reader *r = NULL;
  CHECK_OK(elfm_reader_open(pout, NULL, &r, &err), &err);
  CHECK(elfm_reader_width(r) == 1280 && elfm_reader_height(r) == 720);
  elfm_reader_close(r);
  /* twice: the original */
  CHECK_OK(elfm_events_reverse(pout, NULL, INT64_MIN, INT64_MAX, path_of("back.raw", pback, sizeof pback), &n, &err),
           &err);
  ev_list c = {0};
  CHECK_OK(ev_decode_file(pback, NULL, 4096, &c, &err), &err);
  int same = c.n == a.n;
  for (size_t i = 0; same && i < a.n; i++)
    same = c.t[i] == a.t[i] && c.x[i] == a.x[i] && c.y[i] == a.y[i] && c.p[i] == a.p[i];
  CHECK_MSG(same, "reversed twice: %zu events, not the original %zu", c.n, a.n);
  ev_free(&b);
  ev_free(&c);

  /* a span: [from, to) of the events' times */
  const int64_t from = a.t[40000] + 1, to = a.t[120000];
  size_t i0 = 0, i1 = 0;
  while (i0 < a.n && a.t[i0] < from) i0++;
  i1 = i0;
  while (i1 < a.n && a.t[i1] < to) i1++;
  CHECK_OK(elfm_events_reverse(pin, NULL, from, to, pout, &n, &err), &err);
  CHECK_EQ_INT(n, (int64_t)(i1 - i0));
  ev_list d = {0};
  CHECK_OK(ev_decode_file(pout, NULL, 4096, &d, &err), &err);
  CHECK_MSG(is_reversed(&a, i0, i1, &d), "the span [%" PRId64 ", %" PRId64 ") reversed", from, to);
  ev_free(&d);

  /* a span with no events: an empty file, readable */
  CHECK_OK(elfm_events_reverse(pin, NULL, 1, 2, pout, &n, &err), &err);
  CHECK_EQ_INT(n, 0);
  ev_list e = {0};
  CHECK_OK(ev_decode_file(pout, NULL, 64, &e, &err), &err);
  CHECK_EQ_INT(e.n, 0);
  ev_free(&e);
  /* from >= to: refused */
  CHECK(elfm_events_reverse(pin, NULL, 5, 5, pout, &n, &err) == ELFM_ERR_INVALID && err.message[0]);
  /* an output that cannot be made */
  CHECK(elfm_events_reverse(pin, NULL, INT64_MIN, INT64_MAX, "/nonexistent-dir/x.raw", &n, &err) == ELFM_ERR_IO &&
        strstr(err.file, "nonexistent-dir") != NULL);
  ev_free(&a);
}

static void test_csv_and_bad(void)
{
  char pin[600], pout[600];
  bytes b = {0};
  by_str(&b, "t_us,x,y,p\n10,3,4,1\n20,17,2,0\n35,5,9,1\n");
  by_write(&b, path_of("in.csv", pin, sizeof pin));
  elfm_error err;
  int64_t n = 0;
  CHECK_OK(elfm_events_reverse(pin, NULL, INT64_MIN, INT64_MAX, path_of("csv.raw", pout, sizeof pout), &n, &err),
           &err);
  CHECK_EQ_INT(n, 3);
  ev_list l = {0};
  CHECK_OK(ev_decode_file(pout, NULL, 64, &l, &err), &err);
  CHECK(l.n == 3 && l.t[0] == 10 && l.x[0] == 5 && l.y[0] == 9 && l.p[0] == 0 && l.t[1] == 25 && l.x[1] == 17 &&
        l.p[1] == 1 && l.t[2] == 35 && l.x[2] == 3 && l.p[2] == 0);
  elfm_reader *r = NULL;
  CHECK_OK(elfm_reader_open(pout, NULL, &r, &err), &err);
  CHECK_MSG(elfm_reader_width(r) == 18 && elfm_reader_height(r) == 10, "geometry %dx%d, wanted 18x10",
            elfm_reader_width(r), elfm_reader_height(r));
  elfm_reader_close(r);
  ev_free(&l);

  /* missing */
  CHECK(elfm_events_reverse(path_of("missing.raw", pin, sizeof pin), NULL, INT64_MIN, INT64_MAX, pout, &n, &err) ==
            ELFM_ERR_IO &&
        strstr(err.file, "missing.raw") != NULL);
  /* truncated: a word cut in half after two events */
  b.n = 0;
  const char *hdr = "% evt 3.0\n% format EVT3;height=720;width=1280\n% end\n";
  by_str(&b, hdr);
  by_u16(&b, 0x8000 | 1);          /* TIME_HIGH */
  by_u16(&b, 0x0000 | 3);          /* ADDR_Y 3 */
  by_u16(&b, 0x6000 | 4);          /* TIME_LOW */
  by_u16(&b, 0x2000 | (1u << 11) | 5); /* ADDR_X 5, ON */
  uint8_t half = 0x20;
  by_put(&b, &half, 1);
  by_write(&b, path_of("trunc.raw", pin, sizeof pin));
  elfm_error_clear(&err);
  const elfm_status st = elfm_events_reverse(pin, NULL, INT64_MIN, INT64_MAX, pout, &n, &err);
  char buf[1200];
  fprintf(stderr, "  truncated input -> %s\n", elfm_error_format(&err, buf, sizeof buf));
  CHECK(st == ELFM_ERR_FORMAT && strstr(err.file, "trunc.raw") != NULL &&
        err.offset == (int64_t)strlen(hdr) + 8 && n == 0);
  free(b.b);
}

int main(void)
{
  scratch_make(dir, sizeof dir);
  test_whole_and_span();
  test_csv_and_bad();
  scratch_remove(dir);
  return check_report();
}
