// The byte format the ABI fuzz target (fuzz_abi.cpp) decodes into lt_scene_* calls, shared with
// the seed writer (make_fuzz_seeds.cpp) so that the seeds stay valid programs of the format.
//
// A stream is a sequence of operations: one byte (its value modulo kOpCount picks the operation)
// followed by the operation's fields. Numbers are read front to back; a stream that ends early
// reads zeros. Floats take one byte for small values, (b - 120) / 8 for b < 0xF0 (so -15 to
// 14.875 in steps of 1/8, what most scenes need), and five for any other bit pattern (0xF0, then
// the float's 4 bytes little-endian: NaN, infinities, denormals and huge values).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace lt_fuzz {

enum Op : uint8_t {
  kAddImage = 0,
  kAddMaterial,
  kAddMesh,
  kAddInstance,
  kAddLight,  // type, colour, transform, radius, spot size and blend, shape, sizes, angle, visibility, spread (ABI 20)
  kSetCamera,
  kSetWorld,
  kSetMaterialVolume,
  kSetWorldVolume,
  kSetInstanceTransform,
  kSetMaterial,
  kClearLights,
  kCommit,
  kRender,
  kSetWorldProgram,
  kSetCameraLens,      // kSetCamera's fields, then depth of field and panorama settings (ABI 9)
  kSetInstanceValues,  // instance, visibility, colour, pass index, attributes (ABI 25)
  kSetInstanceMotion,  // instance, step count (i8, any), 5 transforms (ABI 27)
  kOpCount
};

// Bounds that keep one input fast (a few milliseconds): every count the stream gives is reduced
// modulo these.
constexpr int kMaxImageSide = 8;
constexpr int kMaxConstants = 128;
constexpr int kMaxVertices = 32;
constexpr int kMaxTriangles = 32;
constexpr int kMaxSlots = 4;
constexpr int kMaxComponents = 3;
constexpr int kMaxResolution = 8;
constexpr int kMaxSamples = 4;
constexpr int kMaxBounces = 8;

class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}
  bool done() const { return p_ >= end_; }
  uint8_t u8() { return p_ < end_ ? *p_++ : 0; }
  int8_t i8() { return int8_t(u8()); }
  uint32_t u32() {
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= uint32_t(u8()) << (8 * k);
    return v;
  }
  float f32() {
    const uint8_t b = u8();
    if (b < 0xF0) return (int(b) - 120) / 8.0f;
    uint32_t bits = 0;
    for (int k = 0; k < 4; ++k) bits |= uint32_t(u8()) << (8 * k);
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  }
  void floats(float* out, int n) {
    for (int i = 0; i < n; ++i) out[i] = f32();
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
};

class Writer {
 public:
  std::vector<uint8_t> bytes;
  void u8(uint8_t v) { bytes.push_back(v); }
  void i8(int v) { bytes.push_back(uint8_t(int8_t(v))); }
  void u32(uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes.push_back(uint8_t(v >> (8 * k)));
  }
  void op(Op o) { u8(uint8_t(o)); }
  void f32(float v) {
    const float b = v * 8.0f + 120.0f;
    if (b >= 0 && b < 240 && b == std::floor(b)) {
      u8(uint8_t(b));
      return;
    }
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u8(0xF0);
    for (int k = 0; k < 4; ++k) u8(uint8_t(bits >> (8 * k)));
  }
  void floats(const float* v, int n) {
    for (int i = 0; i < n; ++i) f32(v[i]);
  }
};

}  // namespace lt_fuzz
