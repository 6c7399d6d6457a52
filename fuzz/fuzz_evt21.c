/* fuzz_evt21.c — libFuzzer target for the evt21 reader (see fuzz_events_common.h). */
#include "fuzz_events_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char header[] = "% format EVT21;height=720;width=1280\n% end\n";
  fuzz_events_run(data, size, header, sizeof header - 1, "evt21");
  return 0;
}
