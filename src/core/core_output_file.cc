#include "core/core_output_file.h"

#include <cstdio>
#include <stdexcept>

namespace vlab {

void WriteOutputFile(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !written) throw std::runtime_error("cannot write '" + path + "'");
}

}  // namespace vlab
