/* test_frames.c — the framer: windows, representations, polarity, start
 * modes, chunk-boundary independence, bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_recon.h"
#include "frames_test_util.h"

enum { SW = 64, SH = 48 };

static float px(const elfm_frame *f, int x, int y) { return f->data[y * f->w + x]; }

/* every non-zero pixel listed, each listed once */
static int frame_consistent(const elfm_frame *f)
{
  char *seen = calloc((size_t)f->w * f->h, 1);
  int ok = 1;
  for (size_t i = 0; i < f->nnz; i++) {
    if (seen[f->idx[i]]) ok = 0;
    seen[f->idx[i]] = 1;
  }
  for (int i = 0; i < f->w * f->h; i++)
    if (f->data[i] != 0.0f && !seen[i]) ok = 0;
  free(seen);
  return ok;
}

static void test_exp_windows(void)
{
  elfm_error err;
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.start = ELFM_START_AT_TIME;
  o.start_us = 5000000; /* recordings start at arbitrary offsets (SPEC §1) */
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  add_event(c, 4999999, 1, 1, 1);             /* before start: ignored */
  add_event(c, 5000100, 3, 4, 1);
  add_event(c, 5000600, 3, 4, 0);             /* same pixel later: latest wins */
  add_event(c, 5000900, 10, 20, 1);
  add_event(c, 5003500, 7, 7, 1);             /* window 3; windows 1, 2 are empty */
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
  CHECK_EQ_INT(f->index, 0);
  CHECK_EQ_INT(f->t_start_us, 5000000);
  CHECK_EQ_INT(f->t_end_us, 5001000);
  CHECK_EQ_INT(f->t_us, 5001000); /* time surface: window end */
  CHECK_EQ_INT(f->n_events, 3);
  CHECK_EQ_INT(f->nnz, 2);
  CHECK_NEAR(px(f, 3, 4), 255.0 * exp(-400.0 / 1000.0), 1e-3);
  CHECK_NEAR(px(f, 10, 20), 255.0 * exp(-100.0 / 1000.0), 1e-3);
  CHECK(px(f, 1, 1) == 0.0f);
  CHECK(frame_consistent(f));
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
  CHECK_EQ_INT(f->index, 1);
  CHECK_EQ_INT(f->nnz, 0);
  CHECK(px(f, 3, 4) == 0.0f); /* cleared from the previous frame */
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
  CHECK_EQ_INT(f->index, 2);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 0); /* window 3 not closed yet */
  elfm_framer_finish(fr);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
  CHECK_EQ_INT(f->index, 3);
  CHECK_NEAR(px(f, 7, 7), 255.0 * exp(-500.0 / 1000.0), 1e-3);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 0);
  elfm_framer_free(fr);
  elfm_chunk_free(c);
  elfm_frame_free(f);
}

static void test_lin_count_signed(void)
{
  elfm_error err;
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  add_event(c, 100, 2, 2, 1);
  add_event(c, 300, 2, 2, 0);
  add_event(c, 400, 2, 2, 0);
  add_event(c, 500, 5, 5, 1);
  add_event(c, 1100, 6, 6, 1); /* closes window [100, 1100) */
  for (int mode = 0; mode < 4; mode++) {
    elfm_framer_options o;
    elfm_framer_options_default(&o);
    o.tau_us = 800;
    elfm_framer *fr = NULL;
    if (mode == 0) { o.repr = ELFM_REPR_LIN; }
    if (mode == 1) { o.repr = ELFM_REPR_COUNT; }
    if (mode == 2) { o.repr = ELFM_REPR_COUNT; o.polarity = ELFM_POL_SIGNED; }
    if (mode == 3) { o.repr = ELFM_REPR_EXP; o.polarity = ELFM_POL_OFF; }
    CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
    CHECK_OK(elfm_framer_push(fr, c, &err), &err);
    if (mode == 3) {
      /* OFF only: the first OFF event (300) starts the window [300, 1300),
       * which the ON event at 1100 cannot close */
      CHECK_EQ_INT(elfm_framer_next(fr, f), 0);
      elfm_framer_finish(fr);
    }
    CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
    if (mode == 0) {
      CHECK_EQ_INT(f->t_start_us, 100); /* first window starts at the first event */
      CHECK_NEAR(px(f, 2, 2), 255.0 * (1.0 - 700.0 / 800.0), 1e-3);
      CHECK_NEAR(px(f, 5, 5), 255.0 * (1.0 - 600.0 / 800.0), 1e-3);
    } else if (mode == 1) {
      CHECK_EQ_INT(f->t_us, 600); /* accumulation: window centre */
      CHECK_NEAR(px(f, 2, 2), 3.0, 0);
      CHECK_NEAR(px(f, 5, 5), 1.0, 0);
    } else if (mode == 2) {
      CHECK_NEAR(px(f, 2, 2), -1.0, 0);
      CHECK_NEAR(px(f, 5, 5), 1.0, 0);
    } else {
      CHECK_EQ_INT(f->t_start_us, 300);
      CHECK_EQ_INT(f->nnz, 1);
      CHECK_NEAR(px(f, 2, 2), 255.0 * exp(-900.0 / 800.0), 1e-3);
    }
    CHECK(frame_consistent(f));
    elfm_framer_free(fr);
  }
  elfm_chunk_free(c);
  elfm_frame_free(f);
}

/* Signed time surfaces: a pixel takes its latest event's age and sign,
 * whatever came before it in the window (the framer keeps that event in
 * the frame being built as a signed age: frames.c). */
static void test_exp_lin_signed(void)
{
  elfm_error err;
  elfm_event_chunk *c = elfm_chunk_create(64, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  add_event(c, 100, 2, 2, 1);
  add_event(c, 200, 8, 8, 0);
  add_event(c, 300, 2, 2, 0);  /* (2, 2): ON, then OFF last */
  add_event(c, 700, 8, 8, 1);  /* (8, 8): OFF, then ON last */
  add_event(c, 800, 9, 3, 0);  /* (9, 3): OFF only */
  add_event(c, 900, 9, 3, 0);
  add_event(c, 1100, 6, 6, 1); /* closes window [100, 1100) */
  for (int mode = 0; mode < 2; mode++) {
    elfm_framer_options o;
    elfm_framer_options_default(&o);
    o.tau_us = 800;
    o.polarity = ELFM_POL_SIGNED;
    o.repr = mode == 0 ? ELFM_REPR_EXP : ELFM_REPR_LIN;
    elfm_framer *fr = NULL;
    CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
    CHECK_OK(elfm_framer_push(fr, c, &err), &err);
    CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
    CHECK_EQ_INT(f->n_events, 6);
    CHECK_EQ_INT(f->nnz, 3);
    const double a22 = 800, a88 = 400, a93 = 200; /* ages at the window's end */
    if (mode == 0) {
      CHECK_NEAR(px(f, 2, 2), -255.0 * exp(-a22 / 800.0), 1e-3);
      CHECK_NEAR(px(f, 8, 8), 255.0 * exp(-a88 / 800.0), 1e-3);
      CHECK_NEAR(px(f, 9, 3), -255.0 * exp(-a93 / 800.0), 1e-3);
    } else {
      CHECK_NEAR(px(f, 2, 2), -255.0 * (1.0 - a22 / 800.0), 1e-3);
      CHECK_NEAR(px(f, 8, 8), 255.0 * (1.0 - a88 / 800.0), 1e-3);
      CHECK_NEAR(px(f, 9, 3), -255.0 * (1.0 - a93 / 800.0), 1e-3);
    }
    CHECK(frame_consistent(f));
    /* the next frame is built on this one: [1100, 2100) holds (6, 6)
     * alone, age 1000, and the others are cleared */
    elfm_framer_finish(fr);
    CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
    CHECK_EQ_INT(f->nnz, 1);
    CHECK(px(f, 2, 2) == 0.0f && px(f, 8, 8) == 0.0f && px(f, 9, 3) == 0.0f);
    CHECK_NEAR(px(f, 6, 6), mode == 0 ? 255.0 * exp(-1000.0 / 800.0) : 0.0, 1e-3);
    CHECK(frame_consistent(f));
    elfm_framer_free(fr);
  }
  elfm_chunk_free(c);
  elfm_frame_free(f);
}

/* Overlapping windows (stride < dt), and splitting the stream into chunks
 * anywhere gives the same frames. */
static void test_stride_and_chunking(void)
{
  elfm_error err;
  enum { N = 3000 };
  elfm_event_chunk *all = elfm_chunk_create(N, &err);
  uint32_t s = 12345;
  int64_t t = 1000;
  for (int i = 0; i < N; i++) {
    s = s * 1103515245u + 12345u;
    t += (s >> 16) % 7; /* equal times happen */
    add_event(all, t, (int)((s >> 8) % SW), (int)((s >> 20) % SH), (int)(s >> 31));
  }
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.dt_us = 500;
  o.stride_us = 200;
  o.tau_us = 300;
  elfm_framer *a = NULL, *b = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &a, &err), &err);
  CHECK_OK(elfm_framer_create(&o, SW, SH, &b, &err), &err);
  elfm_frame *fa = elfm_frame_create(SW, SH, &err), *fb = elfm_frame_create(SW, SH, &err);
  CHECK_OK(elfm_framer_push(a, all, &err), &err);
  elfm_framer_finish(a);
  /* reference: frames from the whole stream, kept as checksums */
  double sums[200];
  int64_t nevs[200];
  int na = 0;
  while (na < 200 && elfm_framer_next(a, fa)) {
    double sum = 0;
    for (int i = 0; i < SW * SH; i++) sum += fa->data[i] * (1.0 + i % 13);
    CHECK(frame_consistent(fa));
    CHECK_EQ_INT(fa->t_start_us, all->t_us[0] + na * 200);
    /* brute force: events in the window */
    int64_t n = 0;
    for (int i = 0; i < N; i++) n += all->t_us[i] >= fa->t_start_us && all->t_us[i] < fa->t_end_us;
    CHECK_EQ_INT(fa->n_events, n);
    sums[na] = sum;
    nevs[na] = (int64_t)fa->n_events;
    na++;
  }
  CHECK(na > 30);
  /* feed b in chunks of 1..97 events, pulling frames between pushes */
  elfm_event_chunk *c = elfm_chunk_create(128, &err);
  int nb = 0, pos = 0;
  while (pos < N) {
    s = s * 1103515245u + 12345u;
    int len = 1 + (int)((s >> 16) % 97);
    c->n = 0;
    for (int i = 0; i < len && pos < N; i++, pos++)
      add_event(c, all->t_us[pos], all->x[pos], all->y[pos], all->p[pos]);
    CHECK_OK(elfm_framer_push(b, c, &err), &err);
    while (elfm_framer_next(b, fb)) {
      double sum = 0;
      for (int i = 0; i < SW * SH; i++) sum += fb->data[i] * (1.0 + i % 13);
      if (nb < na) {
        CHECK_NEAR(sum, sums[nb], 1e-6 * fabs(sums[nb]) + 1e-9);
        CHECK_EQ_INT(fb->n_events, nevs[nb]);
      }
      nb++;
    }
  }
  elfm_framer_finish(b);
  while (elfm_framer_next(b, fb)) nb++;
  CHECK_EQ_INT(nb, na);
  elfm_framer_free(a);
  elfm_framer_free(b);
  elfm_frame_free(fa);
  elfm_frame_free(fb);
  elfm_chunk_free(all);
  elfm_chunk_free(c);
}

static void test_trigger_start(void)
{
  elfm_error err;
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.start = ELFM_START_FIRST_TRIGGER;
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(16, &err);
  elfm_frame *f = elfm_frame_create(SW, SH, &err);
  add_event(c, 100, 1, 1, 1); /* before any trigger: no window yet */
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  CHECK_EQ_INT(elfm_framer_origin_us(fr), INT64_MIN);
  c->n = 0;
  c->trig[0] = (elfm_trigger){.t_us = 2500, .channel = 0, .value = 1};
  c->n_trig = 1;
  add_event(c, 2000, 2, 2, 1); /* before the trigger: dropped */
  add_event(c, 2700, 3, 3, 1);
  add_event(c, 3600, 4, 4, 1);
  CHECK_OK(elfm_framer_push(fr, c, &err), &err);
  CHECK_EQ_INT(elfm_framer_origin_us(fr), 2500);
  CHECK_EQ_INT(elfm_framer_next(fr, f), 1);
  CHECK_EQ_INT(f->t_start_us, 2500);
  CHECK_EQ_INT(f->nnz, 1);
  CHECK(px(f, 3, 3) > 0.0f && px(f, 2, 2) == 0.0f);
  elfm_framer_free(fr);
  elfm_chunk_free(c);
  elfm_frame_free(f);
}

/* elfm_frame.n_triggers: the rising edges (of the trigger channel, or
 * any) from the start up to each window's end, on the grid from the first
 * event, whatever the chunks: the frames alone tell pulsed light (track's
 * automatic --start each-trigger). Edges at 1500 (rising), 1800 (falling),
 * 2500 (rising, channel 1), 4000 (rising, on a window boundary: the next
 * window's) and 4200 (rising). */
static void test_trigger_count(void)
{
  elfm_error err;
  const elfm_trigger trig[5] = {{.t_us = 1500, .value = 1}, {.t_us = 1800, .value = 0},
                                {.t_us = 2500, .channel = 1, .value = 1},
                                {.t_us = 4000, .value = 1}, {.t_us = 4200, .value = 1}};
  for (int ch = -1; ch <= 0; ch++) {
    for (int split = 0; split < 2; split++) {
      elfm_framer_options o;
      elfm_framer_options_default(&o);
      o.trigger_channel = ch;
      elfm_framer *fr = NULL;
      CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
      elfm_event_chunk *c = elfm_chunk_create(32, &err); /* 20 events */
      elfm_frame *f = elfm_frame_create(SW, SH, &err);
      /* all in one chunk, or the edges and events in two, the first
       * chunk ending at 2000 us */
      for (int part = 0; part < 1 + split; part++) {
        c->n = 0;
        c->n_trig = 0;
        for (int k = 0; k < 5; k++)
          if (!split || (part == 0) == (trig[k].t_us < 2000)) c->trig[c->n_trig++] = trig[k];
        for (int64_t t = 0; t < 5000; t += 250)
          if (!split || (part == 0) == (t < 2000)) add_event(c, t, 1 + (int)(t / 1000), 1, 1);
        CHECK_OK(elfm_framer_push(fr, c, &err), &err);
      }
      elfm_framer_finish(fr);
      /* windows [0,1000) .. [4000,5000) */
      const int64_t any[5] = {0, 1, 2, 2, 4}, ch0[5] = {0, 1, 1, 1, 3};
      int n = 0;
      while (elfm_framer_next(fr, f) == 1 && n < 5) {
        CHECK_EQ_INT(f->t_start_us, 1000 * n);
        const int64_t want = ch < 0 ? any[n] : ch0[n];
        CHECK_EQ_INT(f->n_triggers, want);
        n++;
      }
      CHECK_EQ_INT(n, 5);
      elfm_framer_free(fr);
      elfm_chunk_free(c);
      elfm_frame_free(f);
    }
  }
}

/* ELFM_START_EACH_TRIGGER: every rising edge restarts the grid. Pulses at
 * 2500 (origin), 5300 and 5800 (two edges inside one window), an OFF edge
 * at 3500 that changes nothing, and a pulse at 9000 on a window boundary. */
static void test_each_trigger(void)
{
  elfm_error err;
  for (int repr = 0; repr < 3; repr++) {
    for (int split = 0; split < 2; split++) {
      elfm_framer_options o;
      elfm_framer_options_default(&o);
      o.start = ELFM_START_EACH_TRIGGER;
      o.repr = repr == 0 ? ELFM_REPR_EXP : repr == 1 ? ELFM_REPR_COUNT : ELFM_REPR_INTEGRAL;
      elfm_framer *fr = NULL;
      CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
      elfm_event_chunk *c = elfm_chunk_create(32, &err);
      elfm_frame *f = elfm_frame_create(SW, SH, &err);
      const elfm_trigger trig[5] = {{.t_us = 2500, .value = 1}, {.t_us = 3500, .value = 0},
                                    {.t_us = 5300, .value = 1}, {.t_us = 5800, .value = 1},
                                    {.t_us = 9000, .value = 1}};
      const int64_t ev[9] = {2000, 2600, 5200, 5300, 5700, 5900, 8999, 9000, 12000};
      /* one chunk, or two split between 5700 and 5800 (the edge at 5800
       * arrives with the second, after the window it cuts began) */
      int n_first_ev = split ? 5 : 9, n_first_tr = split ? 3 : 5;
      for (int part = 0; part < 2; part++) {
        c->n = 0;
        c->n_trig = 0;
        for (int k = part ? n_first_tr : 0; k < (part ? 5 : n_first_tr); k++) c->trig[c->n_trig++] = trig[k];
        for (int k = part ? n_first_ev : 0; k < (part ? 9 : n_first_ev); k++)
          add_event(c, ev[k], 1 + k, 1, 1);
        if (c->n || c->n_trig) CHECK_OK(elfm_framer_push(fr, c, &err), &err);
      }
      elfm_framer_finish(fr);
      /* expected windows: [2500,3500) [3500,4500) [4500,5300) [5300,5800)
       * [5800,6800) [6800,7800) [7800,8800) [8800,9000) [9000,10000)
       * [10000,11000) [11000,12000) [12000,13000) */
      const int64_t w0[12] = {2500, 3500, 4500, 5300, 5800, 6800, 7800, 8800, 9000, 10000, 11000, 12000};
      const int64_t w1[12] = {3500, 4500, 5300, 5800, 6800, 7800, 8800, 9000, 10000, 11000, 12000, 13000};
      const size_t nev[12] = {1, 0, 1, 2, 1, 0, 0, 1, 1, 0, 0, 1};
      int n = 0;
      while (elfm_framer_next(fr, f) == 1 && n < 12) {
        CHECK_EQ_INT(f->index, n);
        CHECK_EQ_INT(f->t_start_us, w0[n]);
        CHECK_EQ_INT(f->t_end_us, w1[n]);
        CHECK_EQ_INT(f->n_events, nev[n]);
        CHECK_EQ_INT(f->t_us, repr == 1 ? (w0[n] + w1[n]) / 2 : w1[n]);
        n++;
      }
      CHECK_EQ_INT(n, 12);
      elfm_framer_free(fr);
      elfm_chunk_free(c);
      elfm_frame_free(f);
    }
  }
  /* trigger_channel: only that channel's edges open windows (a second
   * input, e.g. a camera's frame clock on channel 1, must not cut them) */
  {
    elfm_framer_options o;
    elfm_framer_options_default(&o);
    CHECK_EQ_INT(o.trigger_channel, -1);
    o.start = ELFM_START_EACH_TRIGGER;
    o.trigger_channel = 0;
    elfm_framer *fr = NULL;
    CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
    elfm_event_chunk *c = elfm_chunk_create(16, &err);
    elfm_frame *f = elfm_frame_create(SW, SH, &err);
    c->trig[0] = (elfm_trigger){.t_us = 500, .channel = 1, .value = 1};  /* not ours */
    c->trig[1] = (elfm_trigger){.t_us = 1000, .channel = 0, .value = 1}; /* origin */
    c->trig[2] = (elfm_trigger){.t_us = 1400, .channel = 1, .value = 1}; /* not ours */
    c->trig[3] = (elfm_trigger){.t_us = 2600, .channel = 0, .value = 1}; /* cuts [2000, 3000) */
    c->n_trig = 4;
    add_event(c, 700, 1, 1, 1);
    add_event(c, 1200, 2, 1, 1);
    add_event(c, 4000, 3, 1, 1);
    CHECK_OK(elfm_framer_push(fr, c, &err), &err);
    elfm_framer_finish(fr);
    const int64_t w0[5] = {1000, 2000, 2600, 3600, 4600};
    int n = 0;
    while (elfm_framer_next(fr, f) == 1 && n < 5) {
      CHECK_EQ_INT(f->t_start_us, w0[n]);
      n++;
    }
    CHECK_EQ_INT(n, 4); /* the last window, [3600, 4600), holds the last event */
    elfm_framer_free(fr);
    elfm_chunk_free(c);
    elfm_frame_free(f);
    o.trigger_channel = 256;
    CHECK(elfm_framer_create(&o, SW, SH, &fr, &err) == ELFM_ERR_INVALID);
  }
  /* edges out of order are a format error, not a silent misalignment */
  elfm_framer_options o;
  elfm_framer_options_default(&o);
  o.start = ELFM_START_EACH_TRIGGER;
  elfm_framer *fr = NULL;
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(8, &err);
  c->trig[0] = (elfm_trigger){.t_us = 1000, .value = 1};
  c->trig[1] = (elfm_trigger){.t_us = 3000, .value = 1};
  c->trig[2] = (elfm_trigger){.t_us = 2000, .value = 1};
  c->n_trig = 3;
  CHECK(elfm_framer_push(fr, c, &err) == ELFM_ERR_FORMAT);
  CHECK(strstr(err.message, "trigger") != NULL);
  elfm_framer_free(fr);
  elfm_chunk_free(c);
}

static void test_bad_input(void)
{
  elfm_error err;
  elfm_framer_options o;
  elfm_framer *fr = NULL;
  elfm_framer_options_default(&o);
  o.dt_us = 49;
  CHECK(elfm_framer_create(&o, SW, SH, &fr, &err) == ELFM_ERR_INVALID && fr == NULL);
  CHECK(strstr(err.message, "dt_us") != NULL);
  elfm_framer_options_default(&o);
  o.stride_us = 2000;
  CHECK(elfm_framer_create(&o, SW, SH, &fr, &err) == ELFM_ERR_INVALID);
  elfm_framer_options_default(&o);
  o.tau_us = -1;
  CHECK(elfm_framer_create(&o, SW, SH, &fr, &err) == ELFM_ERR_INVALID);
  elfm_framer_options_default(&o);
  o.start = (elfm_frame_start)(ELFM_START_EACH_TRIGGER + 1);
  CHECK(elfm_framer_create(&o, SW, SH, &fr, &err) == ELFM_ERR_INVALID);
  elfm_framer_options_default(&o);
  CHECK(elfm_framer_create(&o, 0, SH, &fr, &err) == ELFM_ERR_INVALID);
  CHECK_OK(elfm_framer_create(&o, SW, SH, &fr, &err), &err);
  elfm_event_chunk *c = elfm_chunk_create(16, &err);
  add_event(c, 100, SW, 0, 1);
  CHECK(elfm_framer_push(fr, c, &err) == ELFM_ERR_RANGE);
  CHECK(strstr(err.message, "outside") != NULL);
  c->n = 0;
  add_event(c, 200, 1, 1, 1);
  add_event(c, 150, 1, 1, 1);
  CHECK(elfm_framer_push(fr, c, &err) == ELFM_ERR_FORMAT);
  elfm_framer_free(fr);
  elfm_framer_free(NULL);
  elfm_frame_free(NULL);
  elfm_chunk_free(c);
}

int main(void)
{
  test_exp_windows();
  test_lin_count_signed();
  test_exp_lin_signed();
  test_stride_and_chunking();
  test_trigger_start();
  test_trigger_count();
  test_each_trigger();
  test_bad_input();
  return check_report();
}
