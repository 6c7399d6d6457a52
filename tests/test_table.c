/* test_table.c — numeric CSV tables: values, empty fields, every error path. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "elfm_tracker.h"

static elfm_status parse(const char *text, elfm_table **t, elfm_error *err)
{
  return elfm_table_parse(text, strlen(text), "mem.csv", t, err);
}

/* The parse fails with `code` at `line`; its message holds `msg` (which
 * names the field, counted from 1), unless msg is NULL. */
static void expect_error_msg(const char *text, elfm_status code, int64_t line, const char *what,
                             const char *msg)
{
  elfm_table *t = NULL;
  elfm_error err;
  elfm_error_clear(&err);
  elfm_status s = parse(text, &t, &err);
  CHECK_MSG(s == code, "%s: got %s (%s)", what, elfm_status_str(s), err.message);
  CHECK_MSG(err.line == line, "%s: line %lld, expected %lld", what, (long long)err.line,
            (long long)line);
  CHECK(strcmp(err.file, "mem.csv") == 0);
  CHECK(t == NULL);
  if (msg) CHECK_MSG(strstr(err.message, msg) != NULL, "%s: message '%s', expected '%s'", what, err.message, msg);
}

static void expect_error(const char *text, elfm_status code, int64_t line, const char *what)
{
  expect_error_msg(text, code, line, what, NULL);
}

int main(void)
{
  elfm_error err;
  elfm_table *t = NULL;
  const char *good = "track_id, t_us ,x_um,raw_x_um\r\n"
                     "1,1000000000000,1.5,\n"
                     "\n"
                     "2,1000000000001,-2e-3,7\n";
  CHECK_OK(parse(good, &t, &err), &err);
  if (t) {
    CHECK_EQ_INT(t->n_rows, 2);
    CHECK_EQ_INT(t->n_cols, 4);
    CHECK_EQ_INT(elfm_table_col(t, "t_us"), 1);
    CHECK_EQ_INT(elfm_table_col(t, "nope"), -1);
    /* 1e12 µs survives as a double exactly (SPEC: times near 1e12 µs). */
    CHECK(elfm_table_get(t, 1, 1) == 1000000000001.0);
    CHECK_NEAR(elfm_table_get(t, 1, 2), -2e-3, 0);
    CHECK(isnan(elfm_table_get(t, 0, 3)));
    CHECK_EQ_INT(t->line[1], 4);
    const char *need[] = {"x_um", "z_um"};
    int cols[2];
    CHECK_EQ_INT(elfm_table_require(t, need, 2, cols, &err), ELFM_ERR_FORMAT);
    CHECK(strstr(err.message, "z_um") != NULL);
  }
  elfm_table_free(t);
  elfm_table_free(NULL);

  /* Header only: a valid table with no rows. */
  CHECK_OK(parse("a,b\n", &t, &err), &err);
  if (t) CHECK_EQ_INT(t->n_rows, 0);
  elfm_table_free(t);

  expect_error("", ELFM_ERR_FORMAT, 1, "empty");
  expect_error("  \n1,2\n", ELFM_ERR_FORMAT, 1, "blank header");
  expect_error("a,,b\n", ELFM_ERR_FORMAT, 1, "unnamed column");
  expect_error("a,b\n1,2\n3\n", ELFM_ERR_FORMAT, 3, "too few fields");
  expect_error("a,b\n1,2,3\n", ELFM_ERR_FORMAT, 2, "too many fields");
  expect_error_msg("a,b\n1,x\n", ELFM_ERR_FORMAT, 2, "text field", "field 2 ('x') is not a number");
  expect_error_msg("a,b,c\n1,2,3\n4,5.5.6,7\n", ELFM_ERR_FORMAT, 3, "trailing garbage",
                   "field 2 ('5.5.6')");
  expect_error_msg("a,b\nnan,1\n", ELFM_ERR_RANGE, 2, "nan", "field 1 ('nan') is not a finite");
  expect_error_msg("a,b\n1,2222222222222222222222222222222222222222222222222222222222222222222\n",
                   ELFM_ERR_FORMAT, 2, "too long", "field 2 is too long");
  expect_error("a,b\n1,inf\n", ELFM_ERR_RANGE, 2, "inf");
  expect_error("a,b\n1,1e999\n", ELFM_ERR_RANGE, 2, "overflow");

  /* Files: missing, NUL byte. */
  CHECK_EQ_INT(elfm_table_load_csv("/nonexistent/truth.csv", &t, &err), ELFM_ERR_IO);
  CHECK(strstr(err.file, "truth.csv") != NULL);
  const char *path = "table_nul.csv";
  FILE *f = fopen(path, "wb");
  if (f) {
    fwrite("a,b\n1,\0002\n", 1, 9, f);
    fclose(f);
    CHECK_EQ_INT(elfm_table_load_csv(path, &t, &err), ELFM_ERR_FORMAT);
    CHECK_EQ_INT(err.offset, 6);
    remove(path);
  }
  return check_report();
}
