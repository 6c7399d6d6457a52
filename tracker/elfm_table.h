/* elfm_table.h — numeric CSV tables: truth.csv, tracks.csv, detections.csv,
 * stimulus.csv (SPEC §5–6).
 *
 * The first line names the columns; every further non-empty line has exactly
 * as many comma-separated fields. A field is a finite number or empty (an
 * empty field reads as NaN: "no value", e.g. the raw position of a frame filled
 * by gap closing). Anything else is an error naming the file and line.
 * Times are stored as double: exact for |t_us| < 2^53 µs (285 years).
 *
 * The whole table is held in memory: these files are outputs whose size is
 * that of the tracks, not of the event recording.
 */
#ifndef ELFM_TABLE_H
#define ELFM_TABLE_H

#include <stddef.h>
#include <stdint.h>

#include "elfm_recon.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct elfm_table {
  size_t n_rows, n_cols;
  char **names;       /* n_cols column names, without surrounding blanks */
  double *values;     /* n_rows x n_cols, row-major; NaN for an empty field */
  int64_t *line;      /* 1-based source line of each row (for messages) */
  char path[512];     /* the file it was read from */
} elfm_table;

/* Read a CSV file. On success *out is a table the caller frees with
 * elfm_table_free; on failure *out is NULL and err names file and line. */
elfm_status elfm_table_load_csv(const char *path, elfm_table **out, elfm_error *err);

/* Parse CSV text held in memory (`name` is used in messages). */
elfm_status elfm_table_parse(const char *text, size_t len, const char *name,
                             elfm_table **out, elfm_error *err);

void elfm_table_free(elfm_table *t);

/* Index of the column called `name`, or -1. */
int elfm_table_col(const elfm_table *t, const char *name);

/* Find several columns at once; fails with ELFM_ERR_FORMAT naming the file
 * and the first missing column. cols[i] receives the index of names[i]. */
elfm_status elfm_table_require(const elfm_table *t, const char *const *names, int n,
                               int *cols, elfm_error *err);

static inline double elfm_table_get(const elfm_table *t, size_t row, int col)
{ return t->values[row * t->n_cols + (size_t)col]; }

#ifdef __cplusplus
}
#endif
#endif
