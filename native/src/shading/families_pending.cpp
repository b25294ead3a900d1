// Placeholders for the maths and texture families until their files land (weak: the families'
// own definitions replace them). TODO(issue 13): delete when nodes_math.cpp and textures.cpp land.
#include "shading/program.h"

namespace lt {

__attribute__((weak)) const OpSignature* math_family_signature(uint32_t) { return nullptr; }
__attribute__((weak)) void exec_math_family(const Instr&, Machine&) {}
__attribute__((weak)) const OpSignature* textures_family_signature(uint32_t) { return nullptr; }
__attribute__((weak)) void exec_textures_family(const Instr&, Machine&) {}

}  // namespace lt
