/* test_events_bad.c — every kind of bad event input gives a clear error
 * naming the file and the byte offset (or line), never a crash or a hang:
 * empty file, header only, truncated header line, truncated last word,
 * random bytes (with and without a header), x/y outside the geometry, a
 * vector running past the width, time going back, unsorted and malformed
 * CSV rows, absurd geometry, a header that never ends; and bad writer
 * arguments. Errors are sticky: the next read repeats them. */
#include "test_events_common.h"

static char dir[256];

static const char *path_of(const char *name)
{
  static char p[600]; /* test driver: one path at a time */
  snprintf(p, sizeof p, "%s/%s", dir, name);
  return p;
}

/* Decode `path` completely; expect status `want` at byte `off` (or line
 * `line` when > 0), and the file named in the error. */
static void expect_read_error(const char *path, const elfm_reader_options *opt, elfm_status want,
                              int64_t off, int64_t line, const char *what)
{
  ev_list l = {0};
  elfm_error err;
  elfm_error_clear(&err);
  elfm_status st = ev_decode_file(path, opt, 64, &l, &err);
  char buf[1200];
  fprintf(stderr, "  %-28s -> %s\n", what, elfm_error_format(&err, buf, sizeof buf));
  CHECK_MSG(st == want, "%s: status %s, wanted %s", what, elfm_status_str(st), elfm_status_str(want));
  CHECK_MSG(strstr(err.file, path) != NULL || strstr(path, err.file) != NULL, "%s: file '%s'", what,
            err.file);
  if (line > 0) CHECK_MSG(err.line == line, "%s: line %lld, wanted %lld", what, (long long)err.line, (long long)line);
  else if (off >= 0) CHECK_MSG(err.offset == off, "%s: offset %lld, wanted %lld", what, (long long)err.offset, (long long)off);
  CHECK(err.message[0] != '\0');
  ev_free(&l);
}

static const char *EVT3_HDR = "% evt 3.0\n% format EVT3;height=720;width=1280\n% end\n";

static void test_files(void)
{
  bytes b = {0};
  size_t h = strlen(EVT3_HDR);

  /* Empty file. */
  by_write(&b, path_of("empty.raw"));
  expect_read_error(path_of("empty.raw"), NULL, ELFM_ERR_FORMAT, 0, 0, "empty file");

  /* Header only: opens, reads zero events (eventlfm info then refuses). */
  by_str(&b, EVT3_HDR);
  by_write(&b, path_of("hdr.raw"));
  {
    ev_list l = {0};
    elfm_error err;
    CHECK_OK(ev_decode_file(path_of("hdr.raw"), NULL, 10, &l, &err), &err);
    CHECK_EQ_INT(l.n, 0);
    ev_free(&l);
  }
  /* Header cut inside a line. */
  b.n = 0;
  by_str(&b, "% evt 3.0\n% geome");
  by_write(&b, path_of("cut_hdr.raw"));
  expect_read_error(path_of("cut_hdr.raw"), NULL, ELFM_ERR_FORMAT, 10, 0, "header cut in a line");

  /* Truncated last word: EVT3 words are 2 bytes. */
  b.n = 0;
  by_str(&b, EVT3_HDR);
  by_u16(&b, 0x8000 | 1);
  by_u16(&b, 0x0000 | 3);
  by_u16(&b, 0x2000 | 4);
  uint8_t half = 0x20;
  by_put(&b, &half, 1);
  by_write(&b, path_of("trunc.raw"));
  expect_read_error(path_of("trunc.raw"), NULL, ELFM_ERR_FORMAT, (int64_t)h + 6, 0, "EVT3 truncated word");
  {
    /* The events before the cut were delivered. */
    ev_list l = {0};
    elfm_error err;
    ev_decode_file(path_of("trunc.raw"), NULL, 10, &l, &err);
    CHECK_EQ_INT(l.n, 1);
    ev_free(&l);
  }
  /* EVT2: 4-byte words, 3 bytes left. */
  b.n = 0;
  by_str(&b, "% evt 2.0\n% geometry 640x480\n% end\n");
  size_t h2 = b.n;
  by_u32(&b, 8u << 28);
  by_put(&b, "abc", 3);
  by_write(&b, path_of("trunc2.raw"));
  expect_read_error(path_of("trunc2.raw"), NULL, ELFM_ERR_FORMAT, (int64_t)h2 + 4, 0, "EVT2 truncated word");

  /* Random bytes without a header. */
  uint64_t s = 99;
  b.n = 0;
  for (int i = 0; i < 5000; i++) {
    uint8_t v = (uint8_t)rng_next(&s);
    if (i == 0) v = 0x7F; /* not '%', not 't' */
    by_put(&b, &v, 1);
  }
  by_write(&b, path_of("random.bin"));
  expect_read_error(path_of("random.bin"), NULL, ELFM_ERR_FORMAT, 0, 0, "random bytes");

  /* Random bytes after each kind of header: an error or a clean end,
   * never a crash or hang; any error names a byte inside the file. */
  const char *hdrs[5] = {EVT3_HDR, "% evt 2.0\n% geometry 640x480\n% end\n",
                         "% format EVT21;height=720;width=1280\n% end\n",
                         "% format EVT21;height=720;width=1280;endianness=legacy\n% end\n",
                         "% Data file containing Event2D events.\n% Width 304\n% Height 240\n"};
  for (int k = 0; k < 5; k++) {
    for (int rep = 0; rep < 20; rep++) {
      b.n = 0;
      by_str(&b, hdrs[k]);
      if (k == 4) by_put(&b, "\0\x08", 2);
      size_t len = 16 + rng_next(&s) % 4000;
      for (size_t i = 0; i < len; i++) {
        uint8_t v = (uint8_t)rng_next(&s);
        by_put(&b, &v, 1);
      }
      by_write(&b, path_of("hdr_random.raw"));
      ev_list l = {0};
      elfm_error err;
      elfm_error_clear(&err);
      elfm_status st = ev_decode_file(path_of("hdr_random.raw"), NULL, 7, &l, &err);
      if (st != ELFM_OK) CHECK(err.offset >= 0 && err.offset < (int64_t)b.n);
      for (size_t i = 1; i < l.n; i++)
        if (l.t[i] < l.t[i - 1]) { CHECK(!"decreasing time delivered"); break; }
      ev_free(&l);
    }
  }

  /* x and y outside the geometry (EVT3), and the word's exact offset. */
  b.n = 0;
  by_str(&b, EVT3_HDR);
  by_u16(&b, 0x8000 | 1);
  by_u16(&b, 0x0000 | 10);
  by_u16(&b, 0x2000 | 1279); /* fine */
  by_u16(&b, 0x2000 | 1300); /* x beyond 1280 */
  by_write(&b, path_of("x_out.raw"));
  expect_read_error(path_of("x_out.raw"), NULL, ELFM_ERR_RANGE, (int64_t)h + 6, 0, "x outside geometry");
  b.n = 0;
  by_str(&b, EVT3_HDR);
  by_u16(&b, 0x8000 | 1);
  by_u16(&b, 0x0000 | 720); /* y beyond 720 */
  by_write(&b, path_of("y_out.raw"));
  expect_read_error(path_of("y_out.raw"), NULL, ELFM_ERR_RANGE, (int64_t)h + 2, 0, "y outside geometry");

  /* A vector running past the width: base 1275, bit 8 -> x 1283. */
  b.n = 0;
  by_str(&b, EVT3_HDR);
  by_u16(&b, 0x8000 | 1);
  by_u16(&b, 0x0000 | 10);
  by_u16(&b, 0x3000 | 1275);
  by_u16(&b, 0x4000 | 0x01F);   /* 1275..1279: fine */
  by_u16(&b, 0x3000 | 1275);
  by_u16(&b, 0x4000 | 0x100);   /* 1283 */
  by_write(&b, path_of("vec_out.raw"));
  expect_read_error(path_of("vec_out.raw"), NULL, ELFM_ERR_RANGE, (int64_t)h + 10, 0, "vector past width");

  /* DAT without geometry: the caller's --geometry applies; x beyond it. */
  b.n = 0;
  by_str(&b, "% Data file containing Event2D events.\n");
  by_put(&b, "\0\x08", 2);
  size_t hd = b.n;
  by_u32(&b, 10);
  by_u32(&b, (5u << 14) | 49u); /* x 49 y 5: fine */
  by_u32(&b, 20);
  by_u32(&b, (5u << 14) | 60u); /* x 60 >= 50 */
  by_write(&b, path_of("geo.dat"));
  {
    elfm_reader_options small = {50, 50, 0};
    expect_read_error(path_of("geo.dat"), &small, ELFM_ERR_RANGE, (int64_t)hd + 8, 0, "DAT x outside --geometry");
    ev_list l = {0};
    elfm_error err;
    CHECK_OK(ev_decode_file(path_of("geo.dat"), NULL, 4, &l, &err), &err); /* no geometry: fine */
    CHECK_EQ_INT(l.n, 2);
    ev_free(&l);
  }

  /* Time going back: TIME_LOW 100 then 50 under one TIME_HIGH. */
  b.n = 0;
  by_str(&b, EVT3_HDR);
  by_u16(&b, 0x8000 | 1);
  by_u16(&b, 0x6000 | 100);
  by_u16(&b, 0x0000 | 10);
  by_u16(&b, 0x2000 | 5);
  by_u16(&b, 0x6000 | 50);
  by_u16(&b, 0x2000 | 6);
  by_write(&b, path_of("back.raw"));
  expect_read_error(path_of("back.raw"), NULL, ELFM_ERR_FORMAT, (int64_t)h + 10, 0, "EVT3 time going back");
  {
    /* Allowed and counted on request (eventlfm info). */
    elfm_reader_options opt = {0, 0, 1};
    ev_list l = {0};
    elfm_error err;
    elfm_reader *r;
    CHECK_OK(ev_decode_file(path_of("back.raw"), &opt, 10, &l, &err), &err);
    CHECK_EQ_INT(l.n, 2);
    CHECK_OK(elfm_reader_open(path_of("back.raw"), &opt, &r, &err), &err);
    elfm_event_chunk *c = elfm_chunk_create(10, &err);
    elfm_reader_read(r, c, &err);
    CHECK_EQ_INT(elfm_reader_backward_steps(r), 1);
    elfm_chunk_free(c);
    elfm_reader_close(r);
    ev_free(&l);
  }

  /* Absurd geometry and overflowing numbers in headers. */
  const char *absurd[4] = {"% evt 3.0\n% geometry 100000x100000\n% end\n",
                           "% evt 3.0\n% format EVT3;height=1;width=2147483648\n% end\n",
                           "% evt 3.0\n% geometry 4096x4096\n% end\n",
                           "% evt 3.0\n% geometry 0x720\n% end\n"};
  for (int k = 0; k < 4; k++) {
    b.n = 0;
    by_str(&b, absurd[k]);
    by_write(&b, path_of("absurd.raw"));
    expect_read_error(path_of("absurd.raw"), NULL, ELFM_ERR_FORMAT, -1, 0, "absurd geometry");
  }
  /* A DAT header with another event size, and an unknown evt version. */
  b.n = 0;
  by_str(&b, "% Data file containing Event2D events.\n");
  by_put(&b, "\0\x10", 2);
  by_write(&b, path_of("size16.dat"));
  expect_read_error(path_of("size16.dat"), NULL, ELFM_ERR_UNSUPPORTED, 39 + 1, 0, "DAT event size 16");
  b.n = 0;
  by_str(&b, "% evt 4.0\n");
  by_write(&b, path_of("evt4.raw"));
  expect_read_error(path_of("evt4.raw"), NULL, ELFM_ERR_UNSUPPORTED, 0, 0, "evt 4.0");

  /* A "header" of 5 MiB without a newline (a file claiming a huge header
   * must not make the reader grow): error, bounded memory. */
  b.n = 0;
  by_str(&b, "% ");
  for (int i = 0; i < (5 << 20) / 64; i++)
    by_str(&b, "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa");
  by_write(&b, path_of("bighdr.raw"));
  expect_read_error(path_of("bighdr.raw"), NULL, ELFM_ERR_FORMAT, 0, 0, "endless header line");

  /* CSV: unsorted, malformed, bad polarity, x outside --geometry, long line. */
  const char *csv_bad[5] = {"t_us,x,y,p\n10,1,1,1\n20,2,2,0\n15,3,3,1\n",
                            "t_us,x,y,p\n10,1,1,1\n12,abc,3,1\n",
                            "t_us,x,y,p\n10,1,1,1\n\n12,3,3,2\n",
                            "t_us,x,y,p\n10,1,1,1\n11,1280,3,1\n",
                            "t_us,x,y,p\n-5,1,1,1\n"};
  int64_t csv_line[5] = {4, 3, 4, 3, 2};
  elfm_status csv_st[5] = {ELFM_ERR_FORMAT, ELFM_ERR_FORMAT, ELFM_ERR_FORMAT, ELFM_ERR_RANGE, ELFM_ERR_FORMAT};
  elfm_reader_options geo = {1280, 720, 0};
  for (int k = 0; k < 5; k++) {
    b.n = 0;
    by_str(&b, csv_bad[k]);
    by_write(&b, path_of("bad.csv"));
    expect_read_error(path_of("bad.csv"), &geo, csv_st[k], -1, csv_line[k], "bad CSV row");
  }
  b.n = 0;
  by_str(&b, "t_us,x,y,p\n1,2,3,");
  for (int i = 0; i < 3000; i++) by_str(&b, "1");
  by_write(&b, path_of("long.csv"));
  expect_read_error(path_of("long.csv"), NULL, ELFM_ERR_FORMAT, -1, 2, "CSV line too long");
  /* A good CSV with CRLF and no final newline reads fine. */
  b.n = 0;
  by_str(&b, "t_us,x,y,p\r\n1,2,3,1\r\n5,6,7,0");
  by_write(&b, path_of("crlf.csv"));
  {
    ev_list l = {0};
    elfm_error err;
    CHECK_OK(ev_decode_file(path_of("crlf.csv"), NULL, 1, &l, &err), &err);
    CHECK_EQ_INT(l.n, 2);
    if (l.n == 2) CHECK(l.t[1] == 5 && l.x[1] == 6 && l.y[1] == 7 && l.p[1] == 0);
    ev_free(&l);
  }

  /* Sticky: after an error, the next read repeats it. */
  {
    elfm_reader *r;
    elfm_error err, err2;
    CHECK_OK(elfm_reader_open(path_of("x_out.raw"), NULL, &r, &err), &err);
    elfm_event_chunk *c = elfm_chunk_create(100, &err);
    CHECK(elfm_reader_read(r, c, &err) == ELFM_ERR_RANGE);
    CHECK_EQ_INT(c->n, 1); /* the event before the bad one */
    CHECK(elfm_reader_read(r, c, &err2) == ELFM_ERR_RANGE && err2.offset == err.offset);
    elfm_chunk_free(c);
    elfm_reader_close(r);
  }
  /* A missing file. */
  {
    elfm_reader *r = (elfm_reader *)1;
    elfm_error err;
    CHECK(elfm_reader_open(path_of("nope.raw"), NULL, &r, &err) == ELFM_ERR_IO && r == NULL);
    CHECK(strstr(err.file, "nope.raw") != NULL);
  }
  free(b.b);
}

static void test_writer(void)
{
  elfm_error err;
  elfm_writer *w;
  CHECK(elfm_writer_open(path_of("w.dat"), ELFM_FMT_DAT, 1280, 720, &w, &err) == ELFM_ERR_UNSUPPORTED);
  CHECK(elfm_writer_open(path_of("w.raw"), ELFM_FMT_EVT3, 4096, 720, &w, &err) == ELFM_ERR_INVALID);
  CHECK(elfm_writer_open("/nonexistent-dir/w.raw", ELFM_FMT_EVT3, 1280, 720, &w, &err) == ELFM_ERR_IO);
  CHECK_OK(elfm_writer_open(path_of("w.raw"), ELFM_FMT_EVT3, 1280, 720, &w, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(4, &err);
  c->n = 2;
  c->t_us[0] = 100; c->x[0] = 1; c->y[0] = 2; c->p[0] = 1;
  c->t_us[1] = 200; c->x[1] = 1280; c->y[1] = 2; c->p[1] = 1; /* x outside */
  CHECK(elfm_writer_write(w, c, &err) == ELFM_ERR_RANGE);
  c->x[1] = 3;
  CHECK_OK(elfm_writer_write(w, c, &err), &err);
  c->n = 1;
  c->t_us[0] = 150; /* before the 200 already written */
  CHECK(elfm_writer_write(w, c, &err) == ELFM_ERR_INVALID);
  c->t_us[0] = 250;
  CHECK_OK(elfm_writer_write(w, c, &err), &err);
  CHECK_OK(elfm_writer_close(w, &err), &err);
  /* Only the accepted events are in the file. */
  ev_list l = {0};
  CHECK_OK(ev_decode_file(path_of("w.raw"), NULL, 10, &l, &err), &err);
  CHECK_EQ_INT(l.n, 3);
  if (l.n == 3) CHECK(l.t[0] == 100 && l.t[1] == 200 && l.t[2] == 250 && l.x[1] == 3);
  ev_free(&l);
  elfm_chunk_free(c);
}

int main(void)
{
  scratch_make(dir, sizeof dir);
  test_files();
  test_writer();
  scratch_remove(dir);
  return check_report();
}
