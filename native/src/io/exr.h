// 32-bit float OpenEXR output of a render's passes, input of such files, and the merge of
// sample-split parts (io/merge.cpp).
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

// An EXR image as Lantern reads it: every channel as float, the header's string attributes.
struct ExrImage {
  int width = 0, height = 0;
  std::vector<ExrChannel> channels;  // in the file's (alphabetical) order
  std::map<std::string, std::string> attributes;
  const ExrChannel* find(const std::string& name) const;
};

// Writes channels (rows bottom to top in memory) to a single-part EXR; string attributes go in the
// header. Writes a temporary file beside `path` and renames it: `path` is either untouched or
// complete. Throws IoError.
void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
               const std::map<std::string, std::string>& attributes);

// Reads a single-part scanline or tiled EXR (pixels false: the header only, channels left empty).
// Throws IoError.
ExrImage read_exr(const std::string& path, bool pixels = true);

// All passes of a render, named as Blender names them in a multilayer EXR (Combined as R, G, B, A),
// plus LightTracing.R/G/B for bidirectional renders (the t = 1 splats inside Combined, which the
// merge needs to pool the Variance pass). The header holds the render's sample range and settings
// (lantern/...) and `extra` attributes.
void write_render_exr(const std::string& path, const RenderJob& job,
                      const std::map<std::string, std::string>& extra = {});

// lt_merge_exr (see lantern.h). Returns a one-line summary.
std::string merge_exr(const std::string& out_path, const std::vector<std::string>& part_paths);

}  // namespace lt
