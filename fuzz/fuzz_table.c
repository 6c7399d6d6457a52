/* fuzz_table.c — libFuzzer target for the numeric CSV table parser, and for
 * what reads tables as objects (elfm_traces.h: tracks, clustered detections). */
#include <stddef.h>
#include <stdint.h>

#include "elfm_tracker.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  elfm_table *t = NULL;
  elfm_error err;
  if (elfm_table_parse((const char *)data, size, "fuzz.csv", &t, &err) == ELFM_OK) {
    /* Touch every cell so ASan sees any out-of-bounds layout. */
    volatile double sum = 0;
    for (size_t r = 0; r < t->n_rows; r++)
      for (size_t c = 0; c < t->n_cols; c++) sum += elfm_table_get(t, r, (int)c);
    /* the same table as tracks and as detections: objects or an error,
     * never a crash (columns missing, ids and times anywhere) */
    for (int mode = 0; mode < 3; mode++) {
      elfm_trace_objects *o = NULL;
      elfm_status st = mode == 2 ? elfm_trace_objects_from_detections(t, 3.0, 2.0, 1, &o, &err)
                                 : elfm_trace_objects_from_tracks(t, mode, &o, &err);
      if (st == ELFM_OK)
        for (size_t i = 0; i < elfm_trace_objects_count(o); i++) {
          elfm_trace_object_info in;
          elfm_trace_objects_info(o, i, &in);
          sum += in.x_um + (double)in.n_points;
        }
      elfm_trace_objects_free(o);
    }
    (void)sum;
  }
  elfm_table_free(t);
  return 0;
}
