/* cmd_simulate.c — eventlfm simulate (not built yet: reports so and fails). */
#include "cli.h"

int cmd_simulate(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("simulate", CLI_FAIL, "not implemented yet");
}
