/* fuzz_table.c — libFuzzer target for the numeric CSV table parser. */
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
    (void)sum;
  }
  elfm_table_free(t);
  return 0;
}
