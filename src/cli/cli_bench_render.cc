// vlab bench render: not built yet (placeholder until the renderer lands).
#include <cstdio>

#include "cli/cli_commands.h"

namespace vlab::cli {

int BenchRender(const BenchArgs&) {
  std::fprintf(stderr, "vlab: error: 'bench render' is not available in this build\n");
  return 2;
}

}  // namespace vlab::cli
