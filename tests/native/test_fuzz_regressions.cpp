// Inputs the fuzz targets (tests/fuzz, docs/testing.md) found, kept as tests: each failed before
// its fix.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/exr.h"
#include "scene_builders.h"

namespace {

void write_bytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

void append(std::vector<uint8_t>& out, const std::string& s) {
  out.insert(out.end(), s.begin(), s.end());
  out.push_back(0);
}

void append_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

}  // namespace

// fuzz_exr_merge: an EXR header attribute whose size field says 2 GB made OpenEXR allocate (and
// clear) 2 GB before it found the file too short: seconds and gigabytes for a 40-byte file.
TEST(FuzzRegressions, ExrAttributeSizeBeyondTheFileIsRefusedBeforeAllocating) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/huge_attribute.exr";
  std::vector<uint8_t> bytes;
  append_u32(bytes, 20000630u);  // magic
  append_u32(bytes, 2);          // version 2, single part, scanlines
  append(bytes, "owner");
  append(bytes, "string");
  append_u32(bytes, 0x7ffffff0u);  // 2 GB
  bytes.insert(bytes.end(), 16, uint8_t('x'));
  write_bytes(path, bytes);
  for (bool pixels : {false, true}) {
    const auto start = std::chrono::steady_clock::now();
    try {
      lt::read_exr(path, pixels);
      FAIL() << "a header claiming 2 GB in a " << bytes.size() << "-byte file was read";
    } catch (const lt::IoError& e) {
      EXPECT_NE(std::string(e.what()).find("header attribute 'owner' claims 2147483632 bytes"), std::string::npos)
          << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 0.5);
  }
  // Through the ABI, as `lantern merge` reads its parts.
  const std::string out = dir.path + "/merged.exr";
  const char* parts[] = {path.c_str()};
  EXPECT_EQ(lt_merge_exr(out.c_str(), parts, 1), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find("claims"), std::string::npos) << lt_last_error();
}
