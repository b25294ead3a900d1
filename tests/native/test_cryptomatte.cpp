// Cryptomatte: MurmurHash3_x86_32 and the specification's float ids, the film's per-pixel (id,
// coverage) slots (sorted, coverage a mean over samples, extra ids dropped), the layers a render
// reads and writes, and merges of sample-split parts (coverage weighted by sample counts).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "core/cryptomatte.h"
#include "core/error.h"
#include "core/film.h"
#include "io/exr.h"
#include "scene_builders.h"

using namespace lt_test;

namespace {

uint32_t hash(const std::string& s) { return lt::murmur3_32(s.data(), s.size(), 0); }

uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

TEST(Cryptomatte, MurmurHash3KnownValues) {
  // Reference values of MurmurHash3_x86_32 (Appleby's SMHasher), seed 0: every tail length.
  EXPECT_EQ(hash(""), 0u);
  EXPECT_EQ(hash("a"), 0x3c2569b2u);
  EXPECT_EQ(hash("ab"), 0x9bbfd75fu);
  EXPECT_EQ(hash("abc"), 0xb3dd93fau);
  EXPECT_EQ(hash("abcd"), 0x43ed676au);
  EXPECT_EQ(hash("hello"), 0x248bfa47u);
  EXPECT_EQ(hash("The quick brown fox jumps over the lazy dog"), 0x2e4ff723u);
  EXPECT_EQ(lt::murmur3_32("hello", 5, 1), 0xbb4abcadu);  // the seed is used
  // The ABI hashes the same bytes (UTF-8 names).
  EXPECT_EQ(lt_cryptomatte_hash("hello", 5), 0x248bfa47u);
}

TEST(Cryptomatte, IdsAreTheHashBitsWithABoundedExponent) {
  // A normal float's bits are kept; exponent 0 (denormal, zero) and 255 (inf, NaN) flip bit 23.
  EXPECT_EQ(bits(lt::cryptomatte_id(0x3f800001u)), 0x3f800001u);
  EXPECT_EQ(bits(lt::cryptomatte_id(0x00012345u)), 0x00812345u);
  EXPECT_EQ(bits(lt::cryptomatte_id(0x80000000u)), 0x80800000u);
  EXPECT_EQ(bits(lt::cryptomatte_id(0x7f800000u)), 0x7f000000u);
  EXPECT_EQ(bits(lt::cryptomatte_id(0xffc00001u)), 0xff400001u);
  for (uint32_t h : {0u, 1u, 0x7fffffffu, 0xffffffffu, hash("Cube")}) {
    const float f = lt::cryptomatte_id(h);
    EXPECT_TRUE(std::isnormal(f)) << h;
  }
}

TEST(Cryptomatte, FilmKeepsTheFirstIdsSortedByCoverage) {
  lt::FilmLayout layout;
  layout.passes = 0;
  layout.cryptomatte = 1u << lt::kCryptoMaterial;
  layout.cryptomatte_levels = 3;  // 2 layers: 4 slots
  lt::Film film(2, 1, layout);
  EXPECT_TRUE(film.has_cryptomatte(lt::kCryptoMaterial));
  EXPECT_FALSE(film.has_cryptomatte(lt::kCryptoObject));
  const float a = lt::cryptomatte_id(hash("A")), b = lt::cryptomatte_id(hash("B")), c = lt::cryptomatte_id(hash("C")),
              d = lt::cryptomatte_id(hash("D")), e = lt::cryptomatte_id(hash("E"));
  // Pixel 0: 10 samples: A once, B 3 times (one of weight 0.5), C 4 times, D once, E once (after
  // four ids: dropped), one background sample (no id) and one of weight 0.
  struct S {
    float id, w;
  };
  const S samples[] = {{a, 1}, {b, 1}, {c, 1}, {b, 0.5f}, {c, 1}, {d, 1}, {e, 1}, {c, 1}, {0, 0}, {c, 1}, {b, 0}};
  for (const S& s : samples) {
    lt::SampleValue v;
    v.crypto_id[lt::kCryptoMaterial] = s.id;
    v.crypto_id[lt::kCryptoObject] = 123.0f;  // not kept
    v.crypto_weight = s.w;
    film.add(0, 0, v);
  }
  film.finish();
  std::vector<float> l0(8), l1(8);
  film.read_cryptomatte_rows(lt::kCryptoMaterial, 0, 0, 1, l0.data());
  film.read_cryptomatte_rows(lt::kCryptoMaterial, 1, 0, 1, l1.data());
  const float n = 11;
  EXPECT_EQ(l0[0], c);
  EXPECT_FLOAT_EQ(l0[1], 4 / n);
  EXPECT_EQ(l0[2], b);
  EXPECT_FLOAT_EQ(l0[3], 1.5f / n);
  // A and D tie: the first to arrive stays first (Cycles' stable insertion sort).
  EXPECT_EQ(l1[0], a);
  EXPECT_FLOAT_EQ(l1[1], 1 / n);
  EXPECT_EQ(l1[2], d);
  EXPECT_FLOAT_EQ(l1[3], 1 / n);
  // Pixel 1: never sampled: empty slots.
  for (int k = 4; k < 8; ++k) EXPECT_EQ(l0[k], 0.0f);
  EXPECT_THROW(film.read_cryptomatte_rows(lt::kCryptoObject, 0, 0, 1, l0.data()), lt::StateError);
  EXPECT_THROW(film.read_cryptomatte_rows(lt::kCryptoMaterial, 2, 0, 1, l0.data()), lt::InvalidArgument);
  // Memory: 8 bytes per slot, only for the types kept.
  lt::FilmLayout off = layout;
  off.cryptomatte = 0;
  EXPECT_EQ(layout.bytes_per_pixel() - off.bytes_per_pixel(), 4u * 8u);
}

// Three objects side by side in front of the camera (and the background between them), with
// their names' hashes; two share a material and an asset.
ScenePtr crypto_scene() {
  ScenePtr s = new_scene();
  const int red = add_diffuse(s.get(), {0.8f, 0.2f, 0.2f}), grey = add_diffuse(s.get(), {0.5f, 0.5f, 0.5f});
  check(lt_scene_set_material_cryptomatte(s.get(), red, hash("Red")), "set_material_cryptomatte");
  check(lt_scene_set_material_cryptomatte(s.get(), grey, hash("Grey")), "set_material_cryptomatte");
  const char* names[] = {"Left", "Middle", "Right"};
  const int materials[] = {red, grey, red};
  const char* assets[] = {"Rig", "Rig", "Right"};
  for (int k = 0; k < 3; ++k) {
    MeshData m = icosphere(0.55f, 2);  // neighbours overlap on screen: pixels of two ids
    lt_mesh_desc md = m.desc();
    int mesh = -1;
    check(lt_scene_add_mesh(s.get(), &md, &mesh), "add_mesh");
    const Xform xf = translate({-1.0f + float(k), 0, 0});
    lt_instance_desc d{};
    d.mesh = mesh;
    std::copy(xf.begin(), xf.end(), d.transform);
    d.materials = &materials[k];
    d.material_count = 1;
    d.visibility = LT_VISIBLE_ALL;
    d.pass_index = k + 1;
    d.cryptomatte_object = hash(names[k]);
    d.cryptomatte_asset = hash(assets[k]);
    int id = -1;
    check(lt_scene_add_instance(s.get(), &d, &id), "add_instance");
  }
  add_light(s.get(), point_light({0, -3, 3}, 500));
  set_world(s.get(), {0.1f, 0.1f, 0.1f}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -5, 0}, {0, 0, 0}), 50));
  check(lt_scene_commit(s.get()), "commit");
  return s;
}

constexpr int kW = 32, kH = 12, kLevels = 6;

lt_render_settings crypto_settings(int offset, int samples) {
  lt_render_settings rs = render_settings(kW, kH, samples, 3);
  rs.sample_offset = offset;
  // Every pass (the default): EXR parts hold them all.
  rs.cryptomatte = LT_CRYPTOMATTE_OBJECT | LT_CRYPTOMATTE_MATERIAL | LT_CRYPTOMATTE_ASSET;
  rs.cryptomatte_levels = kLevels;
  return rs;
}

RenderPtr render(lt_scene* s, const lt_render_settings& rs) {
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "render_wait");
  return r;
}

// Per pixel of an EXR's layers of one type, id -> coverage.
std::vector<std::map<uint32_t, float>> coverage(const lt::ExrImage& img, const std::string& type) {
  std::vector<std::map<uint32_t, float>> out(size_t(img.width) * img.height);
  for (int layer = 0; layer < (kLevels + 1) / 2; ++layer) {
    char prefix[32];
    std::snprintf(prefix, sizeof prefix, "%s%02d.", type.c_str(), layer);
    const lt::ExrChannel* ch[4];
    for (int c = 0; c < 4; ++c) {
      ch[c] = img.find(std::string(prefix) + "rgba"[c]);
      if (!ch[c]) ADD_FAILURE() << "no channel " << prefix << "rgba"[c];
      if (!ch[c]) return out;
    }
    for (size_t i = 0; i < out.size(); ++i)
      for (int pair = 0; pair < 2; ++pair)
        if (ch[2 * pair]->pixels[i] != 0) out[i][bits(ch[2 * pair]->pixels[i])] = ch[2 * pair + 1]->pixels[i];
  }
  return out;
}

TEST(Cryptomatte, RenderedLayersNameTheObjectsAndCoverThePixel) {
  ScenePtr s = crypto_scene();
  RenderPtr r = render(s.get(), crypto_settings(0, 16));
  std::vector<float> index(kW * kH), layer(kW * kH * 4);
  check(lt_render_read_pass(r.get(), LT_PASS_OBJECT_INDEX, index.data(), index.size()), "read IndexOB");
  const uint32_t object_hash[] = {0, hash("Left"), hash("Middle"), hash("Right")};
  int interior = 0;
  for (int type : {LT_CRYPTOMATTE_OBJECT, LT_CRYPTOMATTE_ASSET, LT_CRYPTOMATTE_MATERIAL}) {
    check(lt_render_read_cryptomatte_rows(r.get(), type, 0, 0, kH, layer.data(), layer.size()), "read layer 0");
    for (int y = 1; y + 1 < kH; ++y)
      for (int x = 1; x + 1 < kW; ++x) {
        // Pixels whose 3x3 neighbourhood (the filter's reach) shows one object: one id, coverage 1.
        const float o = index[y * kW + x];
        bool same = true;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) same = same && index[(y + dy) * kW + x + dx] == o;
        if (!same || o == 0) continue;
        interior += type == LT_CRYPTOMATTE_OBJECT;
        const int k = int(o);
        const uint32_t want = type == LT_CRYPTOMATTE_OBJECT  ? object_hash[k]
                              : type == LT_CRYPTOMATTE_ASSET ? hash(k == 3 ? "Right" : "Rig")
                                                             : hash(k == 2 ? "Grey" : "Red");
        const float* p = &layer[4 * (y * kW + x)];
        EXPECT_EQ(bits(p[0]), bits(lt::cryptomatte_id(want))) << type << " at " << x << "," << y;
        EXPECT_NEAR(p[1], 1.0f, 1e-6f);
        EXPECT_EQ(p[2], 0.0f);
        EXPECT_EQ(p[3], 0.0f);
      }
  }
  EXPECT_GT(interior, 30);
  // Unknown type and layer, wrong buffer size.
  EXPECT_EQ(lt_render_read_cryptomatte_rows(r.get(), 3, 0, 0, kH, layer.data(), layer.size()),
            LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_render_read_cryptomatte_rows(r.get(), LT_CRYPTOMATTE_OBJECT, 3, 0, kH, layer.data(), layer.size()),
            LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_render_read_cryptomatte_rows(r.get(), LT_CRYPTOMATTE_OBJECT, 0, 0, kH, layer.data(), 5),
            LT_ERROR_INVALID_ARGUMENT);
  // A type not kept: refused, not zeros. Combined is the same bits with or without Cryptomatte
  // (it draws no random number).
  lt_render_settings off = crypto_settings(0, 16);
  off.cryptomatte = LT_CRYPTOMATTE_MATERIAL;
  RenderPtr r2 = render(s.get(), off);
  EXPECT_EQ(lt_render_read_cryptomatte_rows(r2.get(), LT_CRYPTOMATTE_OBJECT, 0, 0, kH, layer.data(), layer.size()),
            LT_ERROR_STATE);
  off.cryptomatte = 0;
  RenderPtr r3 = render(s.get(), off);
  std::vector<float> on_rgba(kW * kH * 4), off_rgba(kW * kH * 4);
  check(lt_render_read_pass(r.get(), LT_PASS_COMBINED, on_rgba.data(), on_rgba.size()), "read Combined");
  check(lt_render_read_pass(r3.get(), LT_PASS_COMBINED, off_rgba.data(), off_rgba.size()), "read Combined");
  EXPECT_EQ(std::memcmp(on_rgba.data(), off_rgba.data(), on_rgba.size() * sizeof(float)), 0);
}

TEST(Cryptomatte, SplitPartsMergeIntoTheFullRender) {
  ScenePtr s = crypto_scene();
  TempDir dir;
  const std::string full = dir.path + "/full.exr", a = dir.path + "/a.exr", b = dir.path + "/b.exr",
                    out = dir.path + "/merged.exr";
  const std::string key = "cryptomatte/" + std::string("abcdef0") + "/name";
  const char* attrs[] = {key.c_str(), "CryptoObject", nullptr};
  // Uneven parts, so that weighting by sample counts matters.
  check(lt_render_write_exr_attributes(render(s.get(), crypto_settings(0, 24)).get(), full.c_str(), attrs), "full");
  check(lt_render_write_exr_attributes(render(s.get(), crypto_settings(0, 6)).get(), a.c_str(), attrs), "a");
  check(lt_render_write_exr_attributes(render(s.get(), crypto_settings(6, 18)).get(), b.c_str(), attrs), "b");
  const char* parts[] = {b.c_str(), a.c_str()};
  ASSERT_EQ(lt_merge_exr(out.c_str(), parts, 2), LT_OK) << lt_last_error();
  const lt::ExrImage f = lt::read_exr(full), m = lt::read_exr(out), pa = lt::read_exr(a);
  EXPECT_EQ(m.attributes.at(key), "CryptoObject");
  int edges = 0, part_differs = 0;
  for (const char* type : {"CryptoObject", "CryptoMaterial", "CryptoAsset"}) {
    const auto cf = coverage(f, type), cm = coverage(m, type), ca = coverage(pa, type);
    for (size_t i = 0; i < cf.size(); ++i) {
      ASSERT_EQ(cm[i].size(), cf[i].size()) << type << " pixel " << i;
      for (const auto& [id, c] : cf[i]) {
        ASSERT_TRUE(cm[i].count(id)) << type << " pixel " << i;
        EXPECT_NEAR(cm[i].at(id), c, 1e-6f) << type << " pixel " << i;
      }
      edges += cf[i].size() > 1;  // two ids: the coverages of both merge
      part_differs += ca[i] != cf[i];
    }
  }
  EXPECT_GT(edges, 20);         // pixels with fractional coverage of several ids
  EXPECT_GT(part_differs, 10);  // a part alone is another estimate there
  // Different manifests are refused.
  const char* other[] = {key.c_str(), "CryptoOther", nullptr};
  check(lt_render_write_exr_attributes(render(s.get(), crypto_settings(6, 18)).get(), b.c_str(), other), "b'");
  EXPECT_EQ(lt_merge_exr((out + "2").c_str(), parts, 2), LT_ERROR_INVALID_ARGUMENT);
}

}  // namespace
