// lantern.h's enums by name, from lt_abi_layout's table (abi_layout.cpp).
#pragma once

#include <string>

namespace lt {

// The constants of enum `type` (e.g. "lt_integrator") with `prefix` ("LT_INTEGRATOR_") removed,
// comma-separated, the *_COUNT sentinel left out: "PATH, BIDIRECTIONAL, VOLPATH, VOLUME_DEBUG".
std::string abi_enum_names(const char* type, const char* prefix);

}  // namespace lt
