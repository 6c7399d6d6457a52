/* test_events_ref.c — the real recordings in shared/data/events decode to
 * exactly the figures of reference.jsonl and, where a *.ref.csv exists, to
 * exactly its rows; with a tiny chunk (5 events, so vectors straddle chunk
 * ends) and with a large one. Skips (77) when shared/ is absent. */
#include <cjson/cJSON.h>

#include "test_events_common.h"

static int64_t jint(const cJSON *o, const char *key)
{
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  if (!cJSON_IsNumber(v)) {
    fprintf(stderr, "reference.jsonl: no number '%s'\n", key);
    return INT64_MIN;
  }
  return (int64_t)v->valuedouble;
}

static void check_figures(const char *name, const ev_list *l, const cJSON *ref)
{
  int64_t sum_t = 0, sum_x = 0, sum_y = 0, on = 0, mx = 0, my = 0, back = 0;
  for (size_t i = 0; i < l->n; i++) {
    sum_t += l->t[i];
    sum_x += l->x[i];
    sum_y += l->y[i];
    on += l->p[i];
    if (l->x[i] > mx) mx = l->x[i];
    if (l->y[i] > my) my = l->y[i];
    if (i && l->t[i] < l->t[i - 1]) back++;
  }
  fprintf(stderr, "%s: %zu events\n", name, l->n);
  CHECK_EQ_INT(l->n, jint(ref, "events"));
  CHECK(l->n > 0);
  if (!l->n) return;
  CHECK_EQ_INT(l->t[0], jint(ref, "t_first_us"));
  CHECK_EQ_INT(l->t[l->n - 1], jint(ref, "t_last_us"));
  CHECK_EQ_INT(sum_t, jint(ref, "sum_t"));
  CHECK_EQ_INT(sum_x, jint(ref, "sum_x"));
  CHECK_EQ_INT(sum_y, jint(ref, "sum_y"));
  CHECK_EQ_INT(on, jint(ref, "on_events"));
  CHECK_EQ_INT(mx, jint(ref, "max_x"));
  CHECK_EQ_INT(my, jint(ref, "max_y"));
  CHECK_EQ_INT(back, jint(ref, "non_monotonic_steps"));
}

/* Compare with the independent decoder's rows, line by line. */
static void check_rows(const char *csv_path, const ev_list *l)
{
  FILE *f = fopen(csv_path, "r");
  if (!f) return; /* no row reference for this file */
  char line[256];
  size_t i = 0, bad = 0;
  CHECK(fgets(line, sizeof line, f) && !strncmp(line, "t_us,x,y,p", 10));
  while (fgets(line, sizeof line, f)) {
    long long t;
    int x, y, p;
    if (sscanf(line, "%lld,%d,%d,%d", &t, &x, &y, &p) != 4) continue;
    if (i >= l->n || l->t[i] != t || l->x[i] != x || l->y[i] != y || l->p[i] != p) {
      if (bad++ < 5)
        fprintf(stderr, "%s row %zu: want %lld,%d,%d,%d got %lld,%d,%d,%d\n", csv_path, i + 1, t,
                x, y, p, i < l->n ? (long long)l->t[i] : -1LL, i < l->n ? l->x[i] : -1,
                i < l->n ? l->y[i] : -1, i < l->n ? l->p[i] : -1);
    }
    i++;
  }
  fclose(f);
  CHECK_EQ_INT(bad, 0);
  CHECK_EQ_INT(i, l->n);
}

int main(void)
{
  if (!check_have_shared())
    SKIP("%s/data/events/reference.jsonl not found (shared/ recordings absent)", ELFM_SHARED_DIR);
  const char *dir = ELFM_SHARED_DIR "/data/events";
  FILE *f = fopen(ELFM_SHARED_DIR "/data/events/reference.jsonl", "r");
  CHECK(f != NULL);
  if (!f) return check_report();
  char line[4096];
  int files = 0;
  while (fgets(line, sizeof line, f)) {
    cJSON *ref = cJSON_Parse(line);
    if (!ref) continue;
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(ref, "file");
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(ref, "format");
    CHECK(cJSON_IsString(name) && cJSON_IsString(fmt));
    if (!cJSON_IsString(name) || !cJSON_IsString(fmt)) {
      cJSON_Delete(ref);
      continue;
    }
    char path[1024], csv[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name->valuestring);
    snprintf(csv, sizeof csv, "%s", path);
    char *dot = strrchr(csv, '.');
    if (dot) snprintf(dot, sizeof csv - (size_t)(dot - csv), ".ref.csv");

    /* Format detected from the header. */
    elfm_error err;
    elfm_reader *r;
    CHECK_OK(elfm_reader_open(path, NULL, &r, &err), &err);
    if (r) {
      CHECK(!strcmp(elfm_format_name(elfm_reader_format(r)), fmt->valuestring));
      elfm_reader_close(r);
    }
    size_t caps[2] = {5, 1 << 16};
    for (int k = 0; k < 2; k++) {
      ev_list l = {0};
      CHECK_OK(ev_decode_file(path, NULL, caps[k], &l, &err), &err);
      check_figures(name->valuestring, &l, ref);
      check_rows(csv, &l);
      ev_free(&l);
    }
    files++;
    cJSON_Delete(ref);
  }
  fclose(f);
  CHECK(files >= 3);

  /* The ref CSVs themselves read through the CSV reader give the same rows. */
  ev_list a = {0}, b = {0};
  elfm_error err;
  CHECK_OK(ev_decode_file(ELFM_SHARED_DIR "/data/events/evt3_gen41_5k.raw", NULL, 4096, &a, &err), &err);
  CHECK_OK(ev_decode_file(ELFM_SHARED_DIR "/data/events/evt3_gen41_5k.ref.csv", NULL, 7, &b, &err), &err);
  CHECK_EQ_INT(a.n, b.n);
  size_t same = 0;
  for (size_t i = 0; i < a.n && i < b.n; i++)
    same += a.t[i] == b.t[i] && a.x[i] == b.x[i] && a.y[i] == b.y[i] && a.p[i] == b.p[i];
  CHECK_EQ_INT(same, a.n);
  ev_free(&a);
  ev_free(&b);
  return check_report();
}
