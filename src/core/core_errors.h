// Error types of the lab core.
//
// Set-up and loading throw; the CLI catches once, prints one line, and maps the
// type to an exit code: InputError -> 2 (bad scenario, model or option), any
// other std::exception -> 1.
#pragma once

#include <stdexcept>
#include <string>

namespace vlab {

/// Bad user input: a file, key, field or option that cannot be used as given.
/// The message names the file and, where known, the line and key.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace vlab
