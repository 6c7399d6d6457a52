/* cmd_info.c — eventlfm info (not built yet: reports so and fails). */
#include "cli.h"

int cmd_info(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("info", CLI_FAIL, "not implemented yet");
}
