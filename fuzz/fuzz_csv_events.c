/* fuzz_csv_events.c — libFuzzer target for the csv_events reader (see fuzz_events_common.h). */
#include "fuzz_events_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char header[] = "t_us,x,y,p\n";
  fuzz_events_run(data, size, header, sizeof header - 1, "csv_events");
  return 0;
}
