/* cmd_demo.c — eventlfm demo (not built yet: reports so and fails). */
#include "cli.h"

int cmd_demo(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("demo", CLI_FAIL, "not implemented yet");
}
