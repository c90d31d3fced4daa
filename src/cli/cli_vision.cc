// vlab vision: not built yet (placeholder until its issue lands).
#include <cstdio>

#include "cli/cli_commands.h"

namespace vlab::cli {

Subcommand AddVisionCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("vision", "(not available in this build)");
  cmd->group("");  // hidden
  return {cmd, [] {
            std::fprintf(stderr, "vlab: error: 'vision' is not available in this build\n");
            return 2;
          }};
}

}  // namespace vlab::cli
