/* link_test_util.h — what the linker's tests share (include after check.h
 * and elfm_tracker.h). */
#ifndef ELFM_TESTS_LINK_TEST_UTIL_H
#define ELFM_TESTS_LINK_TEST_UTIL_H

/* Finish the linker, drop its tracks, free it. */
static inline void end_linker(elfm_linker *l)
{
  elfm_error err;
  CHECK_OK(elfm_link_finish(l, &err), &err);
  elfm_track *t;
  while ((t = elfm_link_pop_finished(l))) elfm_track_free(t);
  elfm_link_free(l);
}

#endif
