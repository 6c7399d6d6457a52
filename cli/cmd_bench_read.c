/* cmd_bench_read.c — what `eventlfm bench` reads back from a point's run
 * and from a scene: the tracker's summary.json and the stage velocity of
 * the simulator's truth (cmd_bench.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cmd_bench.h"

static const char *const STAGE_KEYS[4] = {"recon_s", "peaks_s", "link_s", "smooth_s"};

/* Depth-first search of a numeric key in a JSON tree. */
static const cJSON *json_find(const cJSON *o, const char *key)
{
  if (!o) return NULL;
  for (const cJSON *c = o->child; c; c = c->next) {
    if (c->string && !strcmp(c->string, key) && cJSON_IsNumber(c)) return c;
    const cJSON *r = json_find(c, key);
    if (r) return r;
  }
  return NULL;
}

/* Numbers from the tracker's summary.json: the volume count (first of a few
 * plausible key names) and the per-stage seconds; -1 / NaN when absent. */
void bench_summary_read(const char *run_dir, double *volumes, double stage_s[4])
{
  *volumes = -1;
  for (int k = 0; k < 4; k++) stage_s[k] = NAN;
  char p[PATH_MAX];
  cli_path_fmt(p, sizeof p, "%s/summary.json", run_dir);
  char *text = cli_read_text(p, BENCH_MAX_TEXT);
  if (!text) return;
  cJSON *o = cJSON_Parse(text);
  free(text);
  static const char *keys[] = {"volumes", "n_volumes", "frames", "n_frames"};
  for (size_t i = 0; i < sizeof keys / sizeof keys[0] && *volumes < 0; i++) {
    const cJSON *n = json_find(o, keys[i]);
    if (n) *volumes = n->valuedouble;
  }
  for (int k = 0; k < 4; k++) {
    const cJSON *n = json_find(o, STAGE_KEYS[k]);
    if (n) stage_s[k] = n->valuedouble;
  }
  cJSON_Delete(o);
}

/* A stage scene moves every bead with the stage: its velocity is the mean
 * over truth ids of (last - first position) / (last - first time). Ids are
 * per pass through the field, so each is one straight segment. */
elfm_status bench_truth_stage_velocity(const char *truth_csv, double v[3], elfm_error *err)
{
  elfm_table *t = NULL;
  elfm_status s = elfm_table_load_csv(truth_csv, &t, err);
  if (s != ELFM_OK) return s;
  static const char *const names[] = {"id", "t_us", "x_um", "y_um", "z_um"};
  int c[5];
  if ((s = elfm_table_require(t, names, 5, c, err)) != ELFM_OK) { elfm_table_free(t); return s; }
  /* first and last row of each id, ids in order of appearance (a stage
   * scene has a few hundred passes; more are not needed for a mean) */
  enum { MAX_IDS = 4096 };
  double *ids = malloc(MAX_IDS * sizeof *ids);
  size_t *first = malloc(MAX_IDS * sizeof *first), *last = malloc(MAX_IDS * sizeof *last);
  if (!ids || !first || !last) {
    free(ids);
    free(first);
    free(last);
    elfm_table_free(t);
    return elfm_error_set(err, ELFM_ERR_NOMEM, NULL, -1, "out of memory");
  }
  int n_ids = 0;
  for (size_t r = 0; r < t->n_rows; r++) {
    double id = elfm_table_get(t, r, c[0]);
    int k = 0;
    while (k < n_ids && ids[k] != id) k++;
    if (k == n_ids) {
      if (n_ids == MAX_IDS) break;
      ids[n_ids] = id;
      first[n_ids] = r;
      n_ids++;
    }
    last[k] = r;
  }
  double sum[3] = {0, 0, 0};
  int n = 0;
  for (int k = 0; k < n_ids; k++) {
    double dt_ms = (elfm_table_get(t, last[k], c[1]) - elfm_table_get(t, first[k], c[1])) * 1e-3;
    if (!(dt_ms > 0)) continue;
    for (int a = 0; a < 3; a++)
      sum[a] += (elfm_table_get(t, last[k], c[2 + a]) - elfm_table_get(t, first[k], c[2 + a])) / dt_ms;
    n++;
  }
  elfm_table_free(t);
  free(ids);
  free(first);
  free(last);
  if (n == 0)
    return elfm_error_set(err, ELFM_ERR_FORMAT, truth_csv, -1, "no moving object in the truth");
  for (int a = 0; a < 3; a++) v[a] = sum[a] / n;
  return ELFM_OK;
}
