/* cmd_convert.c — eventlfm convert (not built yet: reports so and fails). */
#include "cli.h"

int cmd_convert(int argc, char **argv)
{
  (void)argc;
  (void)argv;
  return cli_message("convert", CLI_FAIL, "not implemented yet");
}
