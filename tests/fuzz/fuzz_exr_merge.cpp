// libFuzzer target: the EXR parts `lantern merge` reads (io/exr.cpp, io/merge.cpp). The input is
// one or two part files: a 4-byte little-endian length n, the first part's n bytes, and the rest
// as the second part (no second part when the rest is empty). Each part is read alone (header
// and pixels) and then the parts are merged through lt_merge_exr; every read and merge must
// either succeed or fail with a status and a message.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/exr.h"
#include "lantern/lantern.h"

namespace {

std::string g_dir;

void write(const std::string& path, const uint8_t* data, size_t size) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char dir[] = "/tmp/lantern_fuzz_exr_XXXXXX";
  if (!mkdtemp(dir)) std::abort();
  g_dir = dir;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  uint32_t n = 0;
  std::memcpy(&n, data, 4);
  n = std::min<uint32_t>(n, uint32_t(size - 4));
  std::vector<std::string> paths = {g_dir + "/a.exr"};
  write(paths[0], data + 4, n);
  if (size - 4 - n > 0) {
    paths.push_back(g_dir + "/b.exr");
    write(paths[1], data + 4 + n, size - 4 - n);
  }
  // A valid file may be big: its pixels cost memory, which is no bug. Headers whose pixels would
  // take more than 64 MB are only read, not their pixels nor merged.
  constexpr double kPixelBudget = 64.0 * 1024 * 1024;
  for (const std::string& p : paths) {
    try {
      const lt::ExrImage header = lt::read_exr(p, false);
      if (double(header.width) * header.height * double(header.channels.size()) * 4 > kPixelBudget) return 0;
      lt::read_exr(p, true);
    } catch (const lt::IoError&) {
      // refused with a message: what the reader must do with a bad file
    }
  }
  std::vector<const char*> parts;
  for (const std::string& p : paths) parts.push_back(p.c_str());
  const std::string out = g_dir + "/merged.exr";
  const int status = lt_merge_exr(out.c_str(), parts.data(), int(parts.size()));
  if (status != LT_OK && !*lt_last_error()) {
    std::fprintf(stderr, "merge failed (%d) without a message\n", status);
    std::abort();
  }
  if (status != LT_OK && status != LT_ERROR_IO && status != LT_ERROR_INVALID_ARGUMENT &&
      status != LT_ERROR_OUT_OF_MEMORY) {
    std::fprintf(stderr, "merge failed with status %d: %s\n", status, lt_last_error());
    std::abort();
  }
  return 0;
}
