#include "core/cryptomatte.h"

#include <algorithm>
#include <cstring>
#include <utility>
#include <vector>

namespace lt {

namespace {
inline uint32_t rotl32(uint32_t x, int r) { return (x << r) | (x >> (32 - r)); }
}  // namespace

uint32_t murmur3_32(const void* data, size_t len, uint32_t seed) {
  const uint8_t* bytes = static_cast<const uint8_t*>(data);
  const uint32_t c1 = 0xcc9e2d51u, c2 = 0x1b873593u;
  uint32_t h = seed;
  const size_t blocks = len / 4;
  for (size_t i = 0; i < blocks; ++i) {
    const uint8_t* b = bytes + 4 * i;
    uint32_t k = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
    k *= c1;
    k = rotl32(k, 15);
    k *= c2;
    h ^= k;
    h = rotl32(h, 13);
    h = h * 5 + 0xe6546b64u;
  }
  const uint8_t* tail = bytes + 4 * blocks;
  uint32_t k = 0;
  switch (len & 3) {
    case 3:
      k ^= uint32_t(tail[2]) << 16;
      [[fallthrough]];
    case 2:
      k ^= uint32_t(tail[1]) << 8;
      [[fallthrough]];
    case 1:
      k ^= tail[0];
      k *= c1;
      k = rotl32(k, 15);
      k *= c2;
      h ^= k;
  }
  h ^= uint32_t(len);
  // fmix32
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

float cryptomatte_id(uint32_t hash) {
  uint32_t exponent = (hash >> 23) & 0xffu;
  if (exponent == 0 || exponent == 255) hash ^= 1u << 23;  // the spec's flip: exponent 1 or 254
  float f;
  std::memcpy(&f, &hash, sizeof f);
  return f;
}

void cryptomatte_add(float* pairs, int slots, float id, float weight) {
  if (weight == 0.0f || id == 0.0f) return;
  for (int s = 0; s < slots; ++s) {
    float* p = pairs + 2 * s;
    if (p[0] == 0.0f) {
      p[0] = id;
      p[1] = weight;
      return;
    }
    if (p[0] == id) {
      p[1] += weight;
      return;
    }
  }
}

const char* cryptomatte_type_name(int type) {
  static const char* const kNames[] = {"CryptoObject", "CryptoMaterial", "CryptoAsset"};
  return type >= 0 && type < kCryptoTypes ? kNames[type] : "?";
}

void cryptomatte_top(const float* ids, const double* weights, int count, int slots, float* out_pairs) {
  std::vector<std::pair<float, double>> sum;
  for (int k = 0; k < count; ++k) {
    if (ids[k] == 0.0f || weights[k] == 0.0) continue;
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& e) { return e.first == ids[k]; });
    if (it == sum.end())
      sum.emplace_back(ids[k], weights[k]);
    else
      it->second += weights[k];
  }
  std::stable_sort(sum.begin(), sum.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  for (int s = 0; s < slots; ++s) {
    out_pairs[2 * s] = s < int(sum.size()) ? sum[s].first : 0.0f;
    out_pairs[2 * s + 1] = s < int(sum.size()) ? float(sum[s].second) : 0.0f;
  }
}

void cryptomatte_sort(float* pairs, int slots) {
  for (int s = 1; s < slots && pairs[2 * s] != 0.0f; ++s)
    for (int i = s; i > 0 && pairs[2 * i + 1] > pairs[2 * i - 1]; --i) {
      std::swap(pairs[2 * i], pairs[2 * i - 2]);
      std::swap(pairs[2 * i + 1], pairs[2 * i - 1]);
    }
}

}  // namespace lt
