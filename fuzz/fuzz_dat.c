/* fuzz_dat.c — libFuzzer target for the dat reader (see fuzz_events_common.h). */
#include "fuzz_events_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const char header[] = "% Data file containing Event2D events.\n% Width 640\n% Height 480\n\0\x08";
  fuzz_events_run(data, size, header, sizeof header - 1, "dat");
  return 0;
}
