// Errors a user can cause (bad files, unknown ids, ...). The message is one line that names
// the file and, where it applies, the key or camera, and says what to fix.
#pragma once

#include <stdexcept>
#include <string>

namespace netvmo {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace netvmo
