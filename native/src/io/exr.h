// 32-bit float OpenEXR output of a render's passes.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace lt {

class RenderJob;

struct ExrChannel {
  std::string name;
  std::vector<float> pixels;  // width*height, rows bottom to top
};

// Writes channels (rows bottom to top in memory) to a single-part EXR; string attributes go in the
// header. Throws IoError.
void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
               const std::map<std::string, std::string>& attributes);

// All passes of a render, named as Blender names them in a multilayer EXR (Combined as R, G, B, A).
void write_render_exr(const std::string& path, const RenderJob& job);

}  // namespace lt
