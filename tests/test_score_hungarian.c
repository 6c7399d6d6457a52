/* test_score_hungarian.c — the assignment solver against brute force on
 * random small matrices: square, rectangular both ways, with forbidden
 * (+inf, "outside the gate") entries and whole forbidden rows; workspace
 * reuse and growth; bad input. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

/* Deterministic generator (xorshift64*), so a failure reproduces. */
static double rnd(uint64_t *s)
{
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return (double)((*s * 2685821657736338717ULL) >> 11) / 9007199254740992.0;
}

/* Exhaustive: the best over every partial one-to-one map, ordered by
 * (most non-forbidden pairs, then least cost). */
static void brute(const double *c, int nr, int nc, int r, unsigned used, int cnt, double sum,
                  int *best_cnt, double *best_sum)
{
  if (r == nr) {
    if (cnt > *best_cnt || (cnt == *best_cnt && sum < *best_sum)) {
      *best_cnt = cnt;
      *best_sum = sum;
    }
    return;
  }
  brute(c, nr, nc, r + 1, used, cnt, sum, best_cnt, best_sum); /* row r unassigned */
  for (int j = 0; j < nc; j++) {
    double v = c[r * nc + j];
    if ((used >> j) & 1u || v == INFINITY) continue;
    brute(c, nr, nc, r + 1, used | (1u << j), cnt + 1, sum + v, best_cnt, best_sum);
  }
}

int main(void)
{
  elfm_error err;
  elfm_error_clear(&err);
  elfm_assign_workspace *ws = NULL;
  /* Start at 0 x 0: every larger problem exercises the growth path. */
  CHECK_OK(elfm_assign_workspace_create(0, 0, &ws, &err), &err);
  if (!ws) return check_report();

  uint64_t seed = 0x9E3779B97F4A7C15ULL;
  double cost[64];
  int r2c[8];
  int mismatches = 0, trials = 0;
  for (int trial = 0; trial < 3000; trial++) {
    int nr = 1 + (int)(rnd(&seed) * 6), nc = 1 + (int)(rnd(&seed) * 6);
    double p_forbid = trial % 3 == 0 ? 0.0 : (trial % 3 == 1 ? 0.3 : 0.7);
    for (int k = 0; k < nr * nc; k++) {
      /* integers in some trials: many ties, the hard case for potentials */
      double v = trial % 2 ? floor(rnd(&seed) * 5.0) : rnd(&seed) * 10.0 - 3.0;
      cost[k] = rnd(&seed) < p_forbid ? INFINITY : v;
    }
    if (trial % 7 == 0) /* a row with no allowed column */
      for (int j = 0; j < nc; j++) cost[(nr - 1) * nc + j] = INFINITY;
    double total = -1;
    elfm_status s = elfm_assign_hungarian(cost, nr, nc, r2c, &total, ws, &err);
    CHECK_OK(s, &err);
    int best_cnt = -1;
    double best_sum = INFINITY;
    brute(cost, nr, nc, 0, 0u, 0, 0.0, &best_cnt, &best_sum);
    /* Validate: one-to-one, no forbidden pair, totals consistent. */
    unsigned used = 0;
    int cnt = 0, valid = 1;
    double sum = 0;
    for (int r = 0; r < nr; r++) {
      if (r2c[r] < 0) continue;
      if (r2c[r] >= nc || ((used >> r2c[r]) & 1u) || cost[r * nc + r2c[r]] == INFINITY) valid = 0;
      else {
        used |= 1u << r2c[r];
        cnt++;
        sum += cost[r * nc + r2c[r]];
      }
    }
    trials++;
    if (!valid || cnt != best_cnt || fabs(sum - best_sum) > 1e-9 || fabs(total - sum) > 1e-9) {
      if (mismatches++ < 5)
        fprintf(stderr, "trial %d (%dx%d): got %d pairs cost %.12g (reported %.12g), brute %d "
                "pairs cost %.12g, valid %d\n", trial, nr, nc, cnt, sum, total, best_cnt,
                best_sum, valid);
    }
  }
  CHECK_MSG(mismatches == 0, "%d of %d random problems differ from brute force", mismatches,
            trials);

  /* A known answer: the classic 3x3 (min 5 = 1 + 2 + 2). */
  {
    double c3[9] = {4, 1, 3, 2, 0, 5, 3, 2, 2};
    double total;
    CHECK_OK(elfm_assign_hungarian(c3, 3, 3, r2c, &total, ws, &err), &err);
    CHECK_NEAR(total, 5.0, 1e-12);
    CHECK_EQ_INT(r2c[0], 1);
    CHECK_EQ_INT(r2c[1], 0);
    CHECK_EQ_INT(r2c[2], 2);
  }
  /* Cardinality first: the cheap pair (0,0) would block two matches. */
  {
    double c2[4] = {0.1, 3.9, 3.9, INFINITY};
    double total;
    CHECK_OK(elfm_assign_hungarian(c2, 2, 2, r2c, &total, ws, &err), &err);
    CHECK_EQ_INT(r2c[0], 1);
    CHECK_EQ_INT(r2c[1], 0);
    CHECK_NEAR(total, 7.8, 1e-12);
  }
  /* Empty problems and all forbidden. */
  {
    double c1[2] = {INFINITY, INFINITY};
    CHECK_OK(elfm_assign_hungarian(c1, 1, 2, r2c, NULL, ws, &err), &err);
    CHECK_EQ_INT(r2c[0], -1);
    CHECK_OK(elfm_assign_hungarian(NULL, 3, 0, r2c, NULL, ws, &err), &err);
    CHECK_EQ_INT(r2c[2], -1);
  }
  /* Bad input: NaN and -inf are errors, not silently forbidden. */
  {
    double cn[4] = {1, NAN, 2, 3};
    CHECK(elfm_assign_hungarian(cn, 2, 2, r2c, NULL, ws, &err) == ELFM_ERR_NUMERIC);
    CHECK(strstr(err.message, "NaN") != NULL);
    cn[1] = -INFINITY;
    CHECK(elfm_assign_hungarian(cn, 2, 2, r2c, NULL, ws, &err) == ELFM_ERR_NUMERIC);
    CHECK(elfm_assign_hungarian(cn, -1, 2, r2c, NULL, ws, &err) == ELFM_ERR_INVALID);
    CHECK(elfm_assign_hungarian(cn, 2, 2, r2c, NULL, NULL, &err) == ELFM_ERR_INVALID);
  }
  /* A larger problem: identity-like optimum (diagonal 0, rest >= 1). */
  {
    enum { N = 200 };
    static double big[N * (N + 50)];
    static int rb[N];
    for (int i = 0; i < N; i++)
      for (int j = 0; j < N + 50; j++)
        big[i * (N + 50) + j] = (j == (i * 7) % N) ? 0.0 : 1.0 + rnd(&seed);
    double total = -1;
    CHECK_OK(elfm_assign_hungarian(big, N, N + 50, rb, &total, ws, &err), &err);
    int ok = 1;
    for (int i = 0; i < N; i++) ok &= rb[i] == (i * 7) % N;
    CHECK(ok);
    CHECK_NEAR(total, 0.0, 1e-12);
    /* and its transpose (more rows than columns) */
    static double bt[(N + 50) * N];
    static int rt[N + 50];
    for (int i = 0; i < N; i++)
      for (int j = 0; j < N + 50; j++) bt[j * N + i] = big[i * (N + 50) + j];
    CHECK_OK(elfm_assign_hungarian(bt, N + 50, N, rt, &total, ws, &err), &err);
    int assigned = 0;
    ok = 1;
    for (int j = 0; j < N + 50; j++)
      if (rt[j] >= 0) { assigned++; ok &= j == (rt[j] * 7) % N; }
    CHECK(ok);
    CHECK_EQ_INT(assigned, N);
  }
  elfm_assign_workspace_free(ws);
  elfm_assign_workspace_free(NULL);
  CHECK(elfm_assign_workspace_create(-1, 2, &ws, &err) == ELFM_ERR_INVALID);
  return check_report();
}
