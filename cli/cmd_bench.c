/* cmd_bench.c — eventlfm bench (not built yet: reports so and fails). */
#include "cli.h"

int cmd_bench(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("bench", CLI_FAIL, "not implemented yet");
}
