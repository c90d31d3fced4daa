// Writing a whole text file that vlab makes (an output folder's files, a benchmark's scratch
// files): the counterpart of core_input_file.h's reader for what vlab itself writes.
#pragma once

#include <string>

namespace vlab {

/// Writes `text` to `path` (created or truncated, bytes as given). Throws
/// std::runtime_error "cannot write 'PATH'" when it cannot be opened, written or closed.
void WriteOutputFile(const std::string& path, const std::string& text);

}  // namespace vlab
