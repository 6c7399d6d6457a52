/* test_link_pieces.c — long tracks in bounded memory (elfm_link_take_piece):
 * pieces of a live track tile its frames (each frame is one piece's own),
 * hold exactly the points asked for (own, context before and after), keep
 * the points' values, leave linking alone (the same tracks with and without
 * pieces), and the smoothed pieces written to tracks.csv give every frame
 * of the track once, near the whole track's smoothing. Bad arguments are an
 * ELFM_ERR_INVALID. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"
#include "link_test_util.h"

enum { NF = 1000, PIECE = 200, KEEP = 80, CTX = 30 };

/* Two objects on slow circles, 1 kHz, with noise; frames 300-304 dark
 * for object 1 (a gap the track closes). */
static int frame_dets(int f, elfm_detection d[2], unsigned *seed)
{
  int n = 0;
  for (int k = 0; k < 2; k++) {
    if (k == 1 && f >= 300 && f < 305) continue;
    const double a = 0.004 * f + 3.0 * k;
    *seed = *seed * 1103515245u + 12345u;
    const double e = ((*seed >> 8) & 0xffff) / 65536.0 - 0.5;
    d[n] = link_test_det(40 * k + 12 * cos(a) + 0.1 * e, 12 * sin(a) - 0.1 * e, 5 * sin(2 * a), 1);
    d[n].intensity = 100 + k;
    n++;
  }
  return n;
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_link_options o;
  elfm_link_options_default(&o);
  const int64_t T0 = 1000000000000LL;

  elfm_linker *whole = elfm_link_create(&o, &err), *cut = elfm_link_create(&o, &err);
  CHECK(whole && cut);
  if (!whole || !cut) return check_report();
  elfm_track *t = NULL;
  CHECK_EQ_INT(elfm_link_take_piece(cut, PIECE, 63, 10, &t, &err), ELFM_ERR_INVALID);
  CHECK_EQ_INT(elfm_link_take_piece(cut, PIECE, KEEP, KEEP + 1, &t, &err), ELFM_ERR_INVALID);
  CHECK_EQ_INT(elfm_link_take_piece(cut, 0, KEEP, CTX, &t, &err), ELFM_ERR_INVALID);
  CHECK(t == NULL);

  elfm_track *pieces[64];
  int np = 0;
  unsigned seed = 7;
  for (int f = 0; f < NF; f++) {
    elfm_detection d[2], d2[2];
    const int n = frame_dets(f, d, &seed);
    memcpy(d2, d, sizeof d);
    CHECK_OK(elfm_link_step(whole, f, T0 + 1000LL * f, d, n, &err), &err);
    CHECK_OK(elfm_link_step(cut, f, T0 + 1000LL * f, d2, n, &err), &err);
    do {
      CHECK_OK(elfm_link_take_piece(cut, PIECE, KEEP, CTX, &t, &err), &err);
      if (t && np < 64) pieces[np++] = t;
      else elfm_track_free(t);
    } while (t);
  }
  CHECK_OK(elfm_link_finish(whole, &err), &err);
  CHECK_OK(elfm_link_finish(cut, &err), &err);
  elfm_track *w[2] = {elfm_link_pop_finished(whole), elfm_link_pop_finished(whole)};
  elfm_track *e[2] = {elfm_link_pop_finished(cut), elfm_link_pop_finished(cut)};
  CHECK(w[0] && w[1] && e[0] && e[1] && !elfm_link_pop_finished(whole) &&
        !elfm_link_pop_finished(cut));
  if (!w[0] || !w[1] || !e[0] || !e[1]) return check_report();
  /* 1000 points (995 for the object with the gap): a piece of 200 own
   * points whenever 280 are not yet in one (at 280, 480, 680 and 880
   * points), so 4 pieces each (800 points) and the end with the rest */
  CHECK_EQ_INT(np, 8);
  for (int k = 0; k < 2; k++) {
    const elfm_track *W = w[k], *E = e[k];
    CHECK(E->partial && E->piece == 4 && E->write_to_frame == INT64_MAX);
    /* the pieces, in the order taken, then the end: own frames tile */
    int64_t next_from = INT64_MIN;
    size_t own_total = 0, bad_val = 0;
    int seen = 0;
    for (int i = 0; i <= np; i++) {
      const elfm_track *p = i < np ? pieces[i] : E;
      if (p->id != W->id) continue;
      CHECK(p->partial && p->piece == seen);
      CHECK(p->write_from_frame == next_from);
      next_from = p->write_to_frame;
      size_t own = 0, before = 0, after = 0;
      for (size_t j = 0; j < p->n; j++) {
        const int64_t fr = p->pts[j].frame;
        if (elfm_track_writes_frame(p, fr)) own++;
        else if (i < np && fr >= p->write_to_frame) after++;
        else before++;
        /* the same point as the whole track has at that frame */
        size_t q = 0;
        while (q < W->n && W->pts[q].frame < fr) q++;
        bad_val += q == W->n || W->pts[q].frame != fr || W->pts[q].x_um != p->pts[j].x_um ||
                   W->pts[q].z_um != p->pts[j].z_um;
      }
      own_total += own;
      if (i < np) {
        CHECK_EQ_INT(own, PIECE);
        CHECK_EQ_INT(after, CTX);
        CHECK_EQ_INT(before, seen ? CTX : 0);
        /* what the live track kept: the context before the cut and the
         * last KEEP points */
        CHECK(p->n == (seen ? CTX : 0) + PIECE + CTX);
      } else {
        CHECK_EQ_INT(before, CTX);
      }
      seen++;
    }
    CHECK_EQ_INT(seen, 5);
    CHECK_EQ_INT(own_total, W->n);
    CHECK_EQ_INT(bad_val, 0);
    CHECK_EQ_INT(W->n, k == 0 ? NF : NF - 5);
  }

  /* Smoothed, the pieces' own rows give every frame of the track once,
   * within 0.05 um of the whole track's smoothing away from the ends */
  elfm_smooth_options so;
  elfm_smooth_options_default(&so);
  for (int k = 0; k < 2; k++) {
    CHECK_OK(elfm_track_smooth(w[k], &so, &err), &err);
    int *rows = calloc((size_t)NF, sizeof *rows);
    double worst = 0;
    for (int i = 0; i <= np; i++) {
      elfm_track *p = i < np ? pieces[i] : e[k];
      if (p->id != w[k]->id) continue;
      CHECK_OK(elfm_track_smooth(p, &so, &err), &err);
      for (size_t r = 0; r < p->n_span; r++) {
        const int64_t fr = p->pts[0].frame + (int64_t)r;
        if (!elfm_track_writes_frame(p, fr)) continue;
        rows[fr]++;
        const size_t rw = (size_t)(fr - w[k]->pts[0].frame);
        double d2 = 0;
        for (int a = 0; a < 3; a++) d2 += pow(p->pos_um[3 * r + a] - w[k]->pos_um[3 * rw + a], 2);
        if (fr > 20 && fr < NF - 20 && sqrt(d2) > worst) worst = sqrt(d2);
      }
    }
    int bad_rows = 0;
    for (int f = 0; f < NF; f++) bad_rows += rows[f] != 1;
    CHECK_EQ_INT(bad_rows, 0);
    CHECK(worst < 0.05);
    if (!(worst < 0.05)) fprintf(stderr, "track %d: pieces' rows up to %.3f um off\n", k, worst);
    free(rows);
    /* the info of the pieces folded together is the whole track's */
    elfm_track_info whole_i, acc;
    elfm_track_info_get(w[k], &whole_i);
    int first = 1;
    for (int i = 0; i <= np; i++) {
      elfm_track *p = i < np ? pieces[i] : e[k];
      if (p->id != w[k]->id) continue;
      elfm_track_info pi;
      elfm_track_info_get(p, &pi);
      if (first) acc = pi;
      else elfm_track_info_merge(&acc, &pi);
      first = 0;
    }
    CHECK(acc.n == whole_i.n && acc.first_frame == whole_i.first_frame &&
          acc.last_frame == whole_i.last_frame && acc.n_rows == whole_i.n_rows &&
          acc.n_pieces == 5 && acc.smoothed);
    for (int a = 0; a < 3; a++)
      CHECK_NEAR(acc.mean_vel_um_per_ms[a], whole_i.mean_vel_um_per_ms[a], 1e-3);
    CHECK_NEAR(acc.mean_lateral_speed_um_per_ms, whole_i.mean_lateral_speed_um_per_ms, 1e-3);
  }
  for (int i = 0; i < np; i++) elfm_track_free(pieces[i]);
  for (int k = 0; k < 2; k++) {
    elfm_track_free(w[k]);
    elfm_track_free(e[k]);
  }
  elfm_link_free(whole);
  elfm_link_free(cut);
  return check_report();
}
