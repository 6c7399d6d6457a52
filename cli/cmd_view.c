/* cmd_view.c — eventlfm view (not built yet: reports so and fails). */
#include "cli.h"

int cmd_view(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("view", CLI_FAIL, "not implemented yet");
}
