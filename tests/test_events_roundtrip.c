/* test_events_roundtrip.c — writers and readers agree exactly:
 *  - synthetic events starting at 913 s, crossing two EVT3 time loops and
 *    two gaps longer than 8.4 s, with vector-friendly bursts and triggers:
 *    EVT3 and CSV write -> read give back the same events and triggers,
 *    whatever the chunk sizes on either side (1 .. 64 k);
 *  - hand-encoded EVT3 crossing one and two loops decodes to increasing,
 *    exact times; EVT 2.0, 2.1 (both layouts) and DAT hand-encoded files
 *    decode to the expected events (words before TIME_HIGH dropped);
 *  - seek_us forward, backward, before the start and past the end;
 *  - more triggers than a chunk holds all come through. */
#include "test_events_common.h"

#define W 1280
#define H 720

static void make_events(ev_list *l, uint64_t seed)
{
  uint64_t s = seed;
  int64_t t = 913000000; /* 913 s: EVT2 sample files start there */
  for (int k = 0; k < 120000; k++) {
    uint64_t r = rng_next(&s);
    if (k == 40000) t += 9000000;  /* 9 s gap: > 8.4 s TIME_HIGH step */
    if (k == 80000) t += 21000000; /* 21 s gap: more than a whole loop */
    t += (int64_t)(r % 300);       /* 0..299 us apart, often equal */
    int y = (int)((r >> 10) % H), p = (int)((r >> 30) & 1);
    if ((r >> 40) % 4 == 0) {
      /* A burst on one row, same time and polarity: vector material,
       * sometimes ending at the last column. */
      int len = 2 + (int)((r >> 44) % 30);
      int x = (r >> 50) % 8 == 0 ? W - len : (int)((r >> 20) % (W - 40));
      for (int i = 0; i < len; i++) {
        x += 1 + (int)(((r >> (i % 32)) & 1) & (i % 3 == 0));
        if (x >= W) break;
        ev_push(l, t, x, y, p);
      }
    } else {
      ev_push(l, t, (int)((r >> 20) % W), y, p);
    }
    if ((r >> 56) % 64 == 0) {
      elfm_trigger tr = {t, (uint8_t)((r >> 3) % 16), (uint8_t)((r >> 7) & 1)};
      ev_push_trig(l, tr);
    }
  }
}

/* Write l with chunks of `wcap` events (triggers go with the chunk that
 * covers their time). */
static void write_list(const char *path, elfm_event_format fmt, const ev_list *l, size_t wcap)
{
  elfm_error err;
  elfm_writer *w;
  CHECK_OK(elfm_writer_open(path, fmt, W, H, &w, &err), &err);
  if (!w) return;
  elfm_event_chunk *c = elfm_chunk_create(wcap, &err);
  size_t i = 0, k = 0;
  while (i < l->n || k < l->n_trig) {
    c->n = c->n_trig = 0;
    while (i < l->n && c->n < c->cap) {
      c->t_us[c->n] = l->t[i];
      c->x[c->n] = l->x[i];
      c->y[c->n] = l->y[i];
      c->p[c->n] = l->p[i];
      c->n++;
      i++;
    }
    int64_t t_end = i < l->n ? l->t[i] : INT64_MAX;
    while (k < l->n_trig && l->trig[k].t_us < t_end && c->n_trig < c->cap_trig)
      c->trig[c->n_trig++] = l->trig[k++];
    CHECK_OK(elfm_writer_write(w, c, &err), &err);
  }
  elfm_chunk_free(c);
  CHECK_OK(elfm_writer_close(w, &err), &err);
}

static size_t count_same(const ev_list *a, const ev_list *b)
{
  size_t same = 0;
  for (size_t i = 0; i < a->n && i < b->n; i++)
    same += a->t[i] == b->t[i] && a->x[i] == b->x[i] && a->y[i] == b->y[i] && a->p[i] == b->p[i];
  return same;
}

static size_t count_same_trig(const ev_list *a, const ev_list *b)
{
  size_t same = 0;
  for (size_t i = 0; i < a->n_trig && i < b->n_trig; i++)
    same += a->trig[i].t_us == b->trig[i].t_us && a->trig[i].channel == b->trig[i].channel &&
            a->trig[i].value == b->trig[i].value;
  return same;
}

static void test_roundtrip(const char *dir)
{
  ev_list ref = {0};
  make_events(&ref, 12345);
  char raw[512], csv[512];
  snprintf(raw, sizeof raw, "%s/rt.raw", dir);
  snprintf(csv, sizeof csv, "%s/rt.csv", dir);
  /* The span crosses two 2^24 us loop boundaries. */
  CHECK(ref.t[0] >> 24 != ref.t[ref.n - 1] >> 24);
  CHECK((ref.t[ref.n - 1] >> 24) - (ref.t[0] >> 24) >= 2);

  size_t wcaps[3] = {1, 777, 1 << 16}, rcaps[3] = {1, 11, 1 << 16};
  for (int k = 0; k < 3; k++) {
    write_list(raw, ELFM_FMT_EVT3, &ref, wcaps[k]);
    ev_list got = {0};
    elfm_error err;
    CHECK_OK(ev_decode_file(raw, NULL, rcaps[k], &got, &err), &err);
    CHECK_EQ_INT(got.n, ref.n);
    CHECK_EQ_INT(count_same(&got, &ref), ref.n);
    CHECK_EQ_INT(got.n_trig, ref.n_trig);
    CHECK_EQ_INT(count_same_trig(&got, &ref), ref.n_trig);
    ev_free(&got);
  }
  /* The geometry comes back from the header. */
  elfm_error err;
  elfm_reader *r;
  CHECK_OK(elfm_reader_open(raw, NULL, &r, &err), &err);
  CHECK_EQ_INT(elfm_reader_width(r), W);
  CHECK_EQ_INT(elfm_reader_height(r), H);
  CHECK_EQ_INT(elfm_reader_format(r), ELFM_FMT_EVT3);
  /* How far through the file (progress lines): 0 before the first read,
   * rising with each chunk, 1 at the end */
  CHECK(elfm_reader_fraction(r) == 0);
  {
    elfm_event_chunk *c = elfm_chunk_create(1000, &err);
    double prev = 0;
    int rises = 1, reads = 0;
    while (c && elfm_reader_read(r, c, &err) == ELFM_OK && (c->n || c->n_trig)) {
      const double fr = elfm_reader_fraction(r);
      rises &= fr >= prev && fr <= 1;
      prev = fr;
      reads++;
    }
    CHECK(reads > 10 && rises);
    CHECK(elfm_reader_fraction(r) == 1);
    elfm_chunk_free(c);
  }
  CHECK(elfm_reader_fraction(NULL) == -1);
  elfm_reader_close(r);
  /* Vector words make the file smaller than 2 bytes per event. */
  FILE *f = fopen(raw, "rb");
  fseek(f, 0, SEEK_END);
  long size = ftell(f);
  fclose(f);
  fprintf(stderr, "EVT3: %zu events in %ld bytes (%.2f bytes/event)\n", ref.n, size,
          (double)size / (double)ref.n);
  CHECK((double)size < 2.0 * (double)ref.n);

  /* CSV: events round trip (triggers have no place in CSV). */
  write_list(csv, ELFM_FMT_CSV, &ref, 1000);
  ev_list got = {0};
  elfm_reader_options opt = {W, H, 0};
  CHECK_OK(ev_decode_file(csv, &opt, 333, &got, &err), &err);
  CHECK_EQ_INT(got.n, ref.n);
  CHECK_EQ_INT(count_same(&got, &ref), ref.n);
  ev_free(&got);

  /* Seek: forward, backward, before the start, past the end. */
  CHECK_OK(elfm_reader_open(raw, NULL, &r, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(1000, &err);
  int64_t targets[5] = {ref.t[ref.n / 2], ref.t[ref.n / 4] + 1, 0, ref.t[ref.n - 1] + 1,
                        ref.t[3 * ref.n / 4]};
  for (int k = 0; k < 5; k++) {
    CHECK_OK(elfm_reader_seek_us(r, targets[k], &err), &err);
    size_t want = 0;
    while (want < ref.n && ref.t[want] < targets[k]) want++;
    size_t total = 0, first_ok = 1;
    for (;;) {
      CHECK_OK(elfm_reader_read(r, c, &err), &err);
      if (!c->n && !c->n_trig) break;
      if (total == 0 && c->n)
        first_ok = c->t_us[0] == ref.t[want] && c->x[0] == ref.x[want] && c->y[0] == ref.y[want];
      total += c->n;
      if (k == 0 && total > 5000) break; /* then seek back from mid-stream */
    }
    CHECK_MSG(first_ok, "seek %d to %lld", k, (long long)targets[k]);
    if (k != 0) CHECK_EQ_INT(total, ref.n - want);
  }
  elfm_chunk_free(c);
  elfm_reader_close(r);
  ev_free(&ref);
}

/* EVT3 written by hand: TIME_HIGH climbing by 97 through 4095 -> 0 twice. */
static void test_evt3_loops(const char *dir)
{
  char path[512];
  snprintf(path, sizeof path, "%s/loops.raw", dir);
  bytes b = {0};
  by_str(&b, "% evt 3.0\n% format EVT3;height=720;width=1280\n% end\n");
  by_u16(&b, 0x2000 | 5);   /* ADDR_X before any TIME_HIGH: dropped */
  by_u16(&b, 0x0000 | 7);   /* ADDR_Y before any TIME_HIGH: dropped */
  by_u16(&b, 0x9999);       /* padding */
  int64_t k_end = 2 * 4096 + 500;
  size_t n_expected = 0;
  for (int64_t k = 300; k < k_end; k += 97) {
    by_u16(&b, 0x8000 | (uint32_t)(k & 0xFFF));    /* TIME_HIGH */
    by_u16(&b, 0x6000 | (uint32_t)(k % 4000));     /* TIME_LOW */
    by_u16(&b, 0x0000 | (uint32_t)(k % 720));      /* ADDR_Y */
    by_u16(&b, 0x2800 | (uint32_t)(k % 1280));     /* ADDR_X, ON */
    by_u16(&b, 0x3000 | 100);                      /* VECT_BASE_X 100, OFF */
    by_u16(&b, 0x5000 | 0x81);                     /* VECT_8: x 100 and 107 */
    by_u16(&b, 0x4000 | 0x801);                    /* VECT_12: x 108 and 119 */
    by_u16(&b, 0xA000 | (3 << 8) | 1);             /* EXT_TRIGGER ch 3 rising */
    by_u16(&b, 0x9999);
    n_expected += 5;
  }
  by_write(&b, path);
  free(b.b);
  ev_list got = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(path, NULL, 3, &got, &err), &err);
  CHECK_EQ_INT(got.n, n_expected);
  size_t i = 0, bad = 0, increasing = 1;
  for (int64_t k = 300; k < k_end && i + 5 <= got.n; k += 97) {
    int64_t t = (k << 12) | (k % 4000);
    int xs[5] = {(int)(k % 1280), 100, 107, 108, 119};
    for (int j = 0; j < 5; j++, i++) {
      if (got.t[i] != t || got.x[i] != xs[j] || got.y[i] != k % 720 || got.p[i] != (j == 0))
        bad++;
      if (i && got.t[i] < got.t[i - 1]) increasing = 0;
    }
  }
  CHECK_EQ_INT(bad, 0);
  CHECK(increasing);
  CHECK(got.n && got.t[got.n - 1] > ((int64_t)2 << 24)); /* two loops counted */
  CHECK(got.n_trig > 0 && got.trig[0].channel == 3 && got.trig[0].value == 1);
  ev_free(&got);
}

static void test_evt2(const char *dir)
{
  char path[512];
  snprintf(path, sizeof path, "%s/e2.raw", dir);
  bytes b = {0};
  by_str(&b, "% Date 2020-09-14 09:03:25\n% plugin_name hal_plugin_gen3_fx3\n% evt 2.0\n");
  by_u32(&b, (1u << 28) | (3u << 22) | (10u << 11) | 20u); /* before TIME_HIGH: dropped */
  by_u32(&b, (8u << 28) | 0x10);                          /* TIME_HIGH: t = 0x10 << 6 */
  by_u32(&b, (1u << 28) | (5u << 22) | (10u << 11) | 20u); /* ON  t=1029 x=10 y=20 */
  by_u32(&b, (0u << 28) | (63u << 22) | (639u << 11) | 479u); /* OFF t=1087 */
  by_u32(&b, (0xAu << 28) | (7u << 22) | (2u << 8) | 1u); /* trigger ch 2 at 1031 */
  by_u32(&b, (0xEu << 28) | 12345);                      /* OTHERS: skipped */
  by_u32(&b, (0xAu << 28) | (9u << 22) | (17u << 8) | 0u); /* ch 17 (5 bits) falling at 1033 */
  by_u32(&b, (8u << 28) | 0x11);
  by_u32(&b, (1u << 28) | (0u << 22) | (1u << 11) | 2u);  /* t = 0x11 << 6 = 1088 */
  by_write(&b, path);
  free(b.b);
  ev_list got = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(path, NULL, 2, &got, &err), &err);
  CHECK_EQ_INT(got.n, 3);
  if (got.n == 3) {
    CHECK(got.t[0] == 1029 && got.x[0] == 10 && got.y[0] == 20 && got.p[0] == 1);
    CHECK(got.t[1] == 1087 && got.x[1] == 639 && got.y[1] == 479 && got.p[1] == 0);
    CHECK(got.t[2] == 1088 && got.x[2] == 1 && got.y[2] == 2);
  }
  CHECK_EQ_INT(got.n_trig, 2);
  if (got.n_trig == 2) {
    CHECK(got.trig[0].t_us == 1031 && got.trig[0].channel == 2 && got.trig[0].value == 1);
    CHECK(got.trig[1].t_us == 1033 && got.trig[1].channel == 17 && got.trig[1].value == 0);
  }
  elfm_reader *r;
  CHECK_OK(elfm_reader_open(path, NULL, &r, &err), &err);
  CHECK_EQ_INT(elfm_reader_width(r), 640); /* from the gen3 plugin name */
  CHECK_EQ_INT(elfm_reader_height(r), 480);
  elfm_reader_close(r);
  ev_free(&got);
}

/* header 0: OpenEB's standard EVT 2.1; 1: its IMX636 variant
 * (endianness=legacy); 2: the old "% evt 2.1" header, which is always that
 * variant (OpenEB's legacy EVT 2.1 files) */
static void test_evt21(const char *dir, int header)
{
  static const char *const hdr[3] = {
      "% format EVT21;height=720;width=1280\n% end\n",
      "% format EVT21;height=720;width=1280;endianness=legacy\n% end\n",
      "% evt 2.1\n% geometry 1280x720\n% end\n"};
  const int legacy = header != 0;
  char path[512];
  snprintf(path, sizeof path, "%s/e21_%d.raw", dir, header);
  bytes b = {0};
  by_str(&b, hdr[header]);
  /* word(hi, lo): hi carries type/t/x/y, lo the valid mask. Standard
   * layout stores lo first (a little-endian 64-bit word). */
#define W21(hi, lo) do { if (legacy) { by_u32(&b, hi); by_u32(&b, lo); } \
                         else { by_u32(&b, lo); by_u32(&b, hi); } } while (0)
  W21((8u << 28) | 100u, 0);                                    /* TIME_HIGH 100 */
  W21((1u << 28) | (9u << 22) | (32u << 11) | 5u, 0x0000000Bu);  /* x 32,33,35 */
  W21((0u << 28) | (9u << 22) | (1248u << 11) | 719u, 0x80000000u); /* x 1279 */
  W21((0xAu << 28) | (4u << 22) | (1u << 8) | 0u, 0);           /* trigger ch 1 falling */
  W21((0xAu << 28) | (6u << 22) | (17u << 8) | 1u, 0);          /* ch 17 (5 bits) rising */
#undef W21
  by_write(&b, path);
  free(b.b);
  ev_list got = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(path, NULL, 2, &got, &err), &err);
  CHECK_EQ_INT(got.n, 4);
  int64_t t = (100 << 6) | 9;
  if (got.n == 4) {
    CHECK(got.t[0] == t && got.x[0] == 32 && got.y[0] == 5 && got.p[0] == 1);
    CHECK(got.x[1] == 33 && got.x[2] == 35);
    CHECK(got.x[3] == 1279 && got.y[3] == 719 && got.p[3] == 0);
  }
  CHECK_EQ_INT(got.n_trig, 2);
  if (got.n_trig == 2) {
    CHECK(got.trig[0].t_us == ((100 << 6) | 4) && got.trig[0].channel == 1);
    CHECK(got.trig[1].t_us == ((100 << 6) | 6) && got.trig[1].channel == 17 && got.trig[1].value == 1);
  }
  ev_free(&got);
}

/* EVT 2.0 and 2.1 TIME_HIGH carries t[33:6] in 28 bits: it loops after 2^34
 * us (4.8 h). A drop of half the range or more is a loop; a smaller one is
 * time going back (an error by default). Each file: TIME_HIGH th0, an event
 * at t_low 1, TIME_HIGH th1, an event at t_low 2. */
static void evt2_th_pair(const char *path, int v21, uint32_t th0, uint32_t th1)
{
  bytes b = {0};
  by_str(&b, v21 ? "% format EVT21;height=720;width=1280\n% end\n"
                 : "% format EVT2;height=720;width=1280\n% end\n");
  const uint32_t w[4] = {(8u << 28) | th0, (1u << 28) | (1u << 22) | (3u << 11) | 4u,
                         (8u << 28) | th1, (1u << 28) | (2u << 22) | (5u << 11) | 6u};
  for (int i = 0; i < 4; i++) {
    if (v21) by_u32(&b, i == 1 || i == 3 ? 1u : 0u); /* EVT 2.1: the valid mask first */
    by_u32(&b, w[i]);
  }
  by_write(&b, path);
  free(b.b);
}

static void test_evt2_loops(const char *dir)
{
  char path[512];
  for (int v21 = 0; v21 < 2; v21++) {
    snprintf(path, sizeof path, "%s/loop%d.raw", dir, v21);
    ev_list got = {0};
    elfm_error err;
    /* from the range's top to 4: one loop */
    evt2_th_pair(path, v21, 0x0FFFFFF0u, 4u);
    CHECK_OK(ev_decode_file(path, NULL, 8, &got, &err), &err);
    CHECK_EQ_INT(got.n, 2);
    if (got.n == 2) {
      CHECK(got.t[0] == (((int64_t)0x0FFFFFF0 << 6) | 1));
      CHECK_MSG(got.t[1] == ((((int64_t)1 << 28 | 4) << 6) | 2), "EVT%s after the loop: %lld us",
                v21 ? "2.1" : "2", (long long)got.t[1]);
    }
    ev_free(&got);
    /* a drop of a quarter of the range (2^26 x 64 us, 71 min): not a loop */
    evt2_th_pair(path, v21, 3u << 26, 2u << 26);
    elfm_status st = ev_decode_file(path, NULL, 8, &got, &err);
    CHECK_MSG(st == ELFM_ERR_FORMAT && strstr(err.message, "goes back"), "EVT%s: status %d (%s)",
              v21 ? "2.1" : "2", (int)st, err.message);
    CHECK_EQ_INT(got.n, 1);
    ev_free(&got);
  }
}

static void test_dat(const char *dir)
{
  char path[512];
  snprintf(path, sizeof path, "%s/d.dat", dir);
  bytes b = {0};
  by_str(&b, "% Data file containing Event2D events.\n% Version 2\n% Width 100\n% Height 50\n");
  uint8_t ts[2] = {0, 8};
  by_put(&b, ts, 2);
  by_u32(&b, 0xFFFFFF00u);
  by_u32(&b, (1u << 28) | (49u << 14) | 99u);
  by_u32(&b, 0x10u); /* 32-bit time wrapped */
  by_u32(&b, (0u << 28) | (3u << 14) | 4u);
  by_write(&b, path);
  free(b.b);
  ev_list got = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(path, NULL, 1, &got, &err), &err);
  CHECK_EQ_INT(got.n, 2);
  if (got.n == 2) {
    CHECK(got.t[0] == 0xFFFFFF00 && got.x[0] == 99 && got.y[0] == 49 && got.p[0] == 1);
    CHECK(got.t[1] == ((int64_t)1 << 32) + 0x10 && got.x[1] == 4 && got.y[1] == 3 && got.p[1] == 0);
  }
  elfm_reader *r;
  CHECK_OK(elfm_reader_open(path, NULL, &r, &err), &err);
  CHECK_EQ_INT(elfm_reader_width(r), 100);
  CHECK_EQ_INT(elfm_reader_height(r), 50);
  CHECK_EQ_INT(elfm_reader_format(r), ELFM_FMT_DAT);
  elfm_reader_close(r);
  ev_free(&got);
}

/* 3000 triggers and few events: the 1024-trigger chunk array fills, the
 * reader stops early and hands out the rest on the next reads. */
static void test_many_triggers(const char *dir)
{
  char path[512];
  snprintf(path, sizeof path, "%s/trig.raw", dir);
  ev_list ref = {0};
  for (int i = 0; i < 3000; i++) {
    elfm_trigger tr = {1000 + 10 * i, (uint8_t)(i % 16), (uint8_t)(i & 1)};
    ev_push_trig(&ref, tr);
    if (i % 100 == 0) ev_push(&ref, 1000 + 10 * i + 5, i % W, i % H, 1);
  }
  write_list(path, ELFM_FMT_EVT3, &ref, 5); /* chunks keep times in order */
  ev_list got = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(path, NULL, 4096, &got, &err), &err);
  CHECK_EQ_INT(got.n_trig, 3000);
  CHECK_EQ_INT(count_same_trig(&got, &ref), 3000);
  CHECK_EQ_INT(got.n, ref.n);
  /* Seek back after reading everything: triggers from the target on come
   * again (the reader starts over because it handed out later times). */
  elfm_reader *r;
  CHECK_OK(elfm_reader_open(path, NULL, &r, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  for (;;) {
    CHECK_OK(elfm_reader_read(r, c, &err), &err);
    if (!c->n && !c->n_trig) break;
  }
  int64_t target = ref.trig[2000].t_us;
  CHECK_OK(elfm_reader_seek_us(r, target, &err), &err);
  size_t n_trig = 0, n_ev = 0, first_ok = 1;
  for (;;) {
    CHECK_OK(elfm_reader_read(r, c, &err), &err);
    if (!c->n && !c->n_trig) break;
    for (size_t i = 0; i < c->n_trig; i++) first_ok &= c->trig[i].t_us >= target;
    n_trig += c->n_trig;
    n_ev += c->n;
  }
  CHECK(first_ok);
  CHECK_EQ_INT(n_trig, 1000);
  CHECK_EQ_INT(n_ev, 10); /* events at 1000 + 10 i + 5 for i = 2000, 2100, ... 2900 */
  elfm_chunk_free(c);
  elfm_reader_close(r);
  ev_free(&got);
  ev_free(&ref);
}

int main(void)
{
  char dir[256];
  scratch_make(dir, sizeof dir);
  test_roundtrip(dir);
  test_evt3_loops(dir);
  test_evt2_loops(dir);
  test_evt2(dir);
  test_evt21(dir, 0);
  test_evt21(dir, 1);
  test_evt21(dir, 2);
  test_dat(dir);
  test_many_triggers(dir);
  scratch_remove(dir);
  /* Names and chunk basics. */
  for (int f = ELFM_FMT_EVT3; f <= ELFM_FMT_CSV; f++)
    CHECK_EQ_INT(elfm_format_from_name(elfm_format_name((elfm_event_format)f)), f);
  CHECK_EQ_INT(elfm_format_from_name("evt4"), ELFM_FMT_UNKNOWN);
  elfm_error err;
  CHECK(elfm_chunk_create(0, &err) == NULL && err.code == ELFM_ERR_INVALID);
  elfm_chunk_free(NULL);
  elfm_reader_close(NULL);
  CHECK_OK(elfm_writer_close(NULL, &err), &err);
  return check_report();
}
