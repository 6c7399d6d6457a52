/* fuzz_evt2.c — libFuzzer target for the evt2 reader (see fuzz_events_common.h). */
#include "fuzz_events_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char header[] = "% evt 2.0\n% geometry 640x480\n% end\n";
  fuzz_events_run(data, size, header, sizeof header - 1, "evt2");
  return 0;
}
