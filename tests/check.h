/* check.h — the tiny test harness every tests/test_*.c uses.
 *
 *   CHECK(cond)                 fails the test (keeps going) when cond is false
 *   CHECK_EQ_INT(a, b)          prints both values on failure
 *   CHECK_NEAR(a, b, tol)       |a - b| <= tol, prints values on failure
 *   CHECK_OK(status, err)       status == ELFM_OK, prints the error message
 *   SKIP(msg)                   exit 77 (ctest: skipped) with the message
 *   return check_report();      prints "N passed, N failed" and the exit code
 *
 * One process per file; the counters are per process, so statics are fine
 * here (this is a test driver, not library code).
 */
#ifndef ELFM_TESTS_CHECK_H
#define ELFM_TESTS_CHECK_H

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "elfm_error.h"

static int check_passed_, check_failed_;

#define CHECK(cond)                                                              \
  do {                                                                           \
    if (cond) check_passed_++;                                                   \
    else { check_failed_++;                                                      \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); } \
  } while (0)

#define CHECK_MSG(cond, ...)                                                     \
  do {                                                                           \
    if (cond) check_passed_++;                                                   \
    else { check_failed_++;                                                      \
      fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);   \
      fprintf(stderr, __VA_ARGS__); fputc('\n', stderr); }                       \
  } while (0)

#define CHECK_EQ_INT(a, b)                                                       \
  do {                                                                           \
    long long ca_ = (long long)(a), cb_ = (long long)(b);                        \
    if (ca_ == cb_) check_passed_++;                                             \
    else { check_failed_++;                                                      \
      fprintf(stderr, "%s:%d: CHECK failed: %s == %s (%lld vs %lld)\n",          \
              __FILE__, __LINE__, #a, #b, ca_, cb_); }                           \
  } while (0)

#define CHECK_NEAR(a, b, tol)                                                    \
  do {                                                                           \
    double ca_ = (double)(a), cb_ = (double)(b), ct_ = (double)(tol);            \
    if (fabs(ca_ - cb_) <= ct_) check_passed_++;                                 \
    else { check_failed_++;                                                      \
      fprintf(stderr, "%s:%d: CHECK failed: |%s - %s| <= %s (%.9g vs %.9g)\n",   \
              __FILE__, __LINE__, #a, #b, #tol, ca_, cb_); }                     \
  } while (0)

#define CHECK_OK(status, errp)                                                   \
  do {                                                                           \
    elfm_status cs_ = (status);                                                  \
    if (cs_ == ELFM_OK) check_passed_++;                                         \
    else { char cbuf_[1200]; check_failed_++;                                    \
      fprintf(stderr, "%s:%d: CHECK_OK failed: %s -> %s: %s\n", __FILE__,        \
              __LINE__, #status, elfm_status_str(cs_),                           \
              elfm_error_format((errp), cbuf_, sizeof cbuf_)); }                 \
  } while (0)

#define SKIP(...)                                                                \
  do { fprintf(stderr, "SKIP: "); fprintf(stderr, __VA_ARGS__);                  \
       fputc('\n', stderr); exit(77); } while (0)

static inline int check_report(void)
{
  printf("%d passed, %d failed\n", check_passed_, check_failed_);
  return check_failed_ ? 1 : 0;
}

/* 1 if the shared/ folder with the real recordings is present. */
static inline int check_have_shared(void)
{
  return access(ELFM_SHARED_DIR "/data/events/reference.jsonl", R_OK) == 0;
}

#endif
