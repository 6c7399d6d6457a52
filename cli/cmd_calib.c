/* cmd_calib.c — eventlfm calib (not built yet: reports so and fails). */
#include "cli.h"

int cmd_calib(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("calib", CLI_FAIL, "not implemented yet");
}
