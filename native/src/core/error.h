// Errors inside the core are exceptions; the C ABI turns them into status codes and
// lt_last_error() messages (no exception ever crosses the boundary).
#pragma once

#include <stdexcept>
#include <string>

namespace lt {

struct InvalidArgument : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct StateError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Refused before allocating: what an operation would need exceeds what the process can get.
struct OutOfMemory : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void set_last_error(const std::string& message);
const char* last_error();

}  // namespace lt
