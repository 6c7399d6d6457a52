/* fuzz_evt3.c — libFuzzer target for the evt3 reader (see fuzz_events_common.h). */
#include "fuzz_events_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char header[] = "% evt 3.0\n% format EVT3;height=720;width=1280\n% end\n";
  fuzz_events_run(data, size, header, sizeof header - 1, "evt3");
  return 0;
}
