// Cryptomatte (Friedman and Jones 2015, "Fully Automatic ID Mattes with Support for Motion Blur and
// Transparency"; the specification at github.com/Psyop/Cryptomatte): ids from names by
// MurmurHash3_x86_32, and per pixel a few (id, coverage) slots, as Cycles 3.4 keeps them
// (kernel/film/cryptomatte_passes.h).
#pragma once

#include <cstddef>
#include <cstdint>

namespace lt {

// MurmurHash3_x86_32 (Appleby's reference, little-endian blocks) of `len` bytes.
uint32_t murmur3_32(const void* data, size_t len, uint32_t seed = 0);

// The spec's uint32_to_float32 (Cycles' util_hash_to_float): the hash's bits as a float, the
// exponent kept within [1, 254] so that no id is zero, denormal, infinite or NaN. 0 is never an id:
// an empty slot holds id 0 and weight 0 (Cycles' ID_NONE).
float cryptomatte_id(uint32_t hash);

// The types a render keeps, as lt_cryptomatte's bits, in the order of the passes.
enum CryptomatteType { kCryptoObject = 0, kCryptoMaterial = 1, kCryptoAsset = 2, kCryptoTypes = 3 };
// Cycles' pass names: CryptoObject, CryptoMaterial, CryptoAsset (layer k: the name and "%02d").
const char* cryptomatte_type_name(int type);
// Output layers (CryptoObject00, 01, ...; two ids each) for Blender's Levels (pass_cryptomatte_depth).
inline int cryptomatte_layers(int levels) { return (levels + 1) / 2; }

// Adds `weight` to id's slot among `slots` (id, weight) pairs, or takes the first empty one. When
// every slot holds another id the weight is dropped (Cycles adds it to the last slot, which would
// give that id coverage that is not its own): the ids kept have exact coverage.
void cryptomatte_add(float* pairs, int slots, float id, float weight);
// Pairs of one pixel from several parts (merges): `in` holds `count` (id, weight) pairs of any ids;
// writes to `out` the `slots` pairs of largest summed weight per id, sorted, empty slots zero.
void cryptomatte_top(const float* ids, const double* weights, int count, int slots, float* out_pairs);
// Sorts the pairs by weight, largest first (Cycles' film_sort_cryptomatte_slots, a stable
// insertion sort); empty slots stay last.
void cryptomatte_sort(float* pairs, int slots);

}  // namespace lt
