// libFuzzer target: image files the core reads itself (io/image_file.cpp: OpenImageIO's PNG, JPEG,
// TIFF, TGA and OpenEXR readers behind Lantern's checks, and Lantern's own Radiance HDR decoder).
// The input is written to a file and read with every colour space; each read must give an image
// of finite texels or throw IoError / ImageFileUnsupported / bad_alloc (which the ABI reports).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>

#include "core/error.h"
#include "io/image_file.h"

namespace {
std::string g_path;
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char dir[] = "/tmp/lantern_fuzz_image_XXXXXX";
  if (!mkdtemp(dir)) std::abort();
  g_path = std::string(dir) + "/in";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FILE* f = std::fopen(g_path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
  for (int space = 0; space < 3; ++space) {
    lt::ImageFileRequest r;
    r.path = g_path;
    r.space = lt::FileColorSpace(space);
    r.use_alpha = true;
    try {
      std::unique_ptr<lt::Image> img = lt::read_image_file(r);
      for (int y = 0; y < img->height(); y += 7)
        for (int x = 0; x < img->width(); x += 7) {
          const lt::Vec3 t = img->texel(x, y);
          if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z)) std::abort();
        }
    } catch (const lt::IoError&) {
    } catch (const lt::ImageFileUnsupported&) {
    } catch (const std::bad_alloc&) {  // a header's size beyond memory: the ABI reports it
    }
  }
  return 0;
}
