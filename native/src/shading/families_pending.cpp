// Placeholders for the texture family until its file lands (weak: the families'
// own definitions replace them). TODO(issue 13): delete when textures.cpp lands.
#include "shading/program.h"

namespace lt {

__attribute__((weak)) const OpSignature* textures_family_signature(uint32_t) { return nullptr; }
__attribute__((weak)) void exec_textures_family(const Instr&, Machine&) {}

}  // namespace lt
