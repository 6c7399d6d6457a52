/* table.c — numeric CSV tables (see elfm_table.h). */
#include "elfm_table.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A file larger than this is not a table we wrote: refuse rather than try to
 * hold it (1 GiB is ~20 M rows of tracks.csv). */
#define TABLE_MAX_BYTES ((size_t)1 << 30)

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/* Trim [*b, *e) of blanks. */
static void trim(const char **b, const char **e)
{
  while (*b < *e && is_blank(**b)) (*b)++;
  while (*e > *b && is_blank((*e)[-1])) (*e)--;
}

static size_t count_fields(const char *b, const char *e)
{
  size_t n = 1;
  for (const char *p = b; p < e; p++) n += (*p == ',');
  return n;
}

static elfm_status parse_number(const char *b, const char *e, double *out, const char *name,
                                int64_t line, size_t field, elfm_error *err)
{
  trim(&b, &e);
  if (b == e) { *out = NAN; return ELFM_OK; }
  char buf[64];
  size_t n = (size_t)(e - b);
  if (n >= sizeof buf)
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, line,
                               "field %zu is too long to be a number", field + 1);
  memcpy(buf, b, n);
  buf[n] = '\0';
  char *end = NULL;
  errno = 0;
  double v = strtod(buf, &end);
  if (end == buf || *end != '\0')
    return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, line,
                               "field %zu ('%s') is not a number", field + 1, buf);
  if (!isfinite(v) || errno == ERANGE)
    return elfm_error_set_line(err, ELFM_ERR_RANGE, name, line,
                               "field %zu ('%s') is not a finite number", field + 1, buf);
  *out = v;
  return ELFM_OK;
}

void elfm_table_free(elfm_table *t)
{
  if (!t) return;
  if (t->names)
    for (size_t i = 0; i < t->n_cols; i++) free(t->names[i]);
  free(t->names);
  free(t->values);
  free(t->line);
  free(t);
}

elfm_status elfm_table_parse(const char *text, size_t len, const char *name,
                             elfm_table **out, elfm_error *err)
{
  *out = NULL;
  if (!name) name = "<memory>";
  const char *end = text + len;
  /* Header: the first line. */
  const char *hb = text, *he = memchr(text, '\n', len);
  if (!he) he = end;
  {
    const char *b = hb, *e = he;
    trim(&b, &e);
    if (len == 0 || b == e)
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, 1,
                                 "empty file: expected a header line naming the columns");
  }
  elfm_table *t = calloc(1, sizeof *t);
  if (!t) return elfm_error_set(err, ELFM_ERR_NOMEM, name, -1, "out of memory");
  snprintf(t->path, sizeof t->path, "%s", name);
  t->n_cols = count_fields(hb, he);
  t->names = calloc(t->n_cols, sizeof *t->names);
  if (!t->names) goto nomem;
  {
    const char *fb = hb;
    for (size_t c = 0; c < t->n_cols; c++) {
      const char *fe = memchr(fb, ',', (size_t)(he - fb));
      if (!fe) fe = he;
      const char *b = fb, *e = fe;
      trim(&b, &e);
      if (b == e) {
        elfm_table_free(t);
        return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, 1, "column %zu has no name", c + 1);
      }
      t->names[c] = malloc((size_t)(e - b) + 1);
      if (!t->names[c]) goto nomem;
      memcpy(t->names[c], b, (size_t)(e - b));
      t->names[c][e - b] = '\0';
      fb = fe + 1;
    }
  }
  /* Rows: at most one per remaining newline (+1). */
  size_t cap_rows = 1;
  for (const char *p = he; p < end; p++) cap_rows += (*p == '\n');
  t->values = malloc(cap_rows * t->n_cols * sizeof *t->values);
  t->line = malloc(cap_rows * sizeof *t->line);
  if (!t->values || !t->line) goto nomem;

  int64_t line = 1;
  const char *p = he < end ? he + 1 : end;
  while (p < end) {
    line++;
    const char *le = memchr(p, '\n', (size_t)(end - p));
    if (!le) le = end;
    const char *b = p, *e = le;
    trim(&b, &e);
    if (b != e) {
      size_t nf = count_fields(p, le);
      if (nf != t->n_cols) {
        size_t n_cols = t->n_cols;
        elfm_table_free(t);
        return elfm_error_set_line(err, ELFM_ERR_FORMAT, name, line,
                                   "%zu fields where the header names %zu", nf, n_cols);
      }
      double *row = t->values + t->n_rows * t->n_cols;
      const char *fb = p;
      for (size_t c = 0; c < t->n_cols; c++) {
        const char *fe = memchr(fb, ',', (size_t)(le - fb));
        if (!fe) fe = le;
        elfm_status s = parse_number(fb, fe, &row[c], name, line, c, err);
        if (s != ELFM_OK) { elfm_table_free(t); return s; }
        fb = fe + 1;
      }
      t->line[t->n_rows++] = line;
    }
    p = le + 1;
  }
  *out = t;
  return ELFM_OK;
nomem:
  elfm_table_free(t);
  return elfm_error_set(err, ELFM_ERR_NOMEM, name, -1, "out of memory reading the table");
}

elfm_status elfm_table_load_csv(const char *path, elfm_table **out, elfm_error *err)
{
  *out = NULL;
  FILE *f = fopen(path, "rb");
  if (!f) return elfm_error_set(err, ELFM_ERR_IO, path, -1, "cannot open: %s", strerror(errno));
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap);
  if (!buf) { fclose(f); return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory"); }
  for (;;) {
    if (len == cap) {
      if (cap >= TABLE_MAX_BYTES) {
        free(buf);
        fclose(f);
        return elfm_error_set(err, ELFM_ERR_RANGE, path, (int64_t)len,
                              "file larger than %zu bytes: not a table", TABLE_MAX_BYTES);
      }
      char *nb = realloc(buf, cap * 2);
      if (!nb) { free(buf); fclose(f); return elfm_error_set(err, ELFM_ERR_NOMEM, path, -1, "out of memory"); }
      buf = nb;
      cap *= 2;
    }
    size_t got = fread(buf + len, 1, cap - len, f);
    len += got;
    if (got == 0) break;
  }
  int failed = ferror(f);
  fclose(f);
  if (failed) {
    free(buf);
    return elfm_error_set(err, ELFM_ERR_IO, path, (int64_t)len, "read failed");
  }
  if (memchr(buf, '\0', len)) {
    size_t at = (size_t)((char *)memchr(buf, '\0', len) - buf);
    free(buf);
    return elfm_error_set(err, ELFM_ERR_FORMAT, path, (int64_t)at, "NUL byte: not a text table");
  }
  elfm_status s = elfm_table_parse(buf, len, path, out, err);
  free(buf);
  return s;
}

int elfm_table_col(const elfm_table *t, const char *name)
{
  for (size_t c = 0; c < t->n_cols; c++)
    if (!strcmp(t->names[c], name)) return (int)c;
  return -1;
}

elfm_status elfm_table_require(const elfm_table *t, const char *const *names, int n,
                               int *cols, elfm_error *err)
{
  for (int i = 0; i < n; i++) {
    cols[i] = elfm_table_col(t, names[i]);
    if (cols[i] < 0)
      return elfm_error_set_line(err, ELFM_ERR_FORMAT, t->path, 1,
                                 "no column '%s' in the header", names[i]);
  }
  return ELFM_OK;
}
