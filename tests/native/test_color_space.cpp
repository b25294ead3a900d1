// io/color_space: Cycles' image half conversions bit for bit, and OpenColorIO's conversion to scene
// linear of Blender's own configuration (Cycles against Blender pixel by pixel:
// tests/blender/test_nodes_inputs.py test_image_colour_space_as_cycles).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "core/error.h"
#include "io/color_space.h"

namespace lt {

TEST(ColorSpace, CyclesHalvesTruncateFlushAndClamp) {
  EXPECT_EQ(cycles_float_to_half(1.0f), 0x3c00);
  EXPECT_EQ(cycles_float_to_half(-2.0f), 0xc000);
  // Truncated, not rounded: the largest float below 1 + 2^-10 stays at 1.
  EXPECT_EQ(cycles_float_to_half(std::nextafter(1.0f + 0x1p-10f, 0.0f)), 0x3c00);
  EXPECT_EQ(cycles_float_to_half(0x1p-15f), 0);   // below the normal range: 0
  EXPECT_EQ(cycles_float_to_half(1e9f), 0x7bff);  // clamped to 65504
  EXPECT_EQ(cycles_half_to_float(0x3c00), 1.0f);
  EXPECT_EQ(cycles_half_to_float(0x3555), 0x1.554p-2f);
  EXPECT_EQ(cycles_half_to_float(0), 0x1p-15f);  // Cycles' reading of a zero half
}

TEST(ColorSpace, FilmicLogToSceneLinearIsBlendersAllocation) {
  const char* config = "/usr/share/blender/datafiles/colormanagement/config.ocio";
  if (!std::ifstream(config)) GTEST_SKIP() << "no Blender configuration at " << config;
  // Filmic Log's to_reference: an inverse lg2 allocation over [-12.473931188, 4.026068812].
  uint16_t px[3] = {cycles_float_to_half(0.25f), cycles_float_to_half(0.5f), cycles_float_to_half(0.75f)};
  float in[3];
  for (int k = 0; k < 3; ++k) in[k] = cycles_half_to_float(px[k]);
  halves_to_scene_linear(config, "Filmic Log", px, 1, 3);
  for (int k = 0; k < 3; ++k) {
    const float expected = std::exp2(in[k] * (4.026068812f + 12.473931188f) - 12.473931188f);
    EXPECT_NEAR(cycles_half_to_float(px[k]), expected, expected * 2e-3f) << k;
  }
  EXPECT_THROW(halves_to_scene_linear(config, "No Such Space", px, 1, 3), InvalidArgument);
}

TEST(ColorSpace, AssociatedColoursAreConvertedUnassociated) {
  // Cycles' processor_apply_pixels_rgba: colours divided by an alpha other than 0 and 1 before
  // the conversion and multiplied after it; alpha itself unchanged.
  const char* config = "/usr/share/blender/datafiles/colormanagement/config.ocio";
  if (!std::ifstream(config)) GTEST_SKIP() << "no Blender configuration at " << config;
  const auto filmic_log = [](float v) { return std::exp2(v * (4.026068812f + 12.473931188f) - 12.473931188f); };
  const float alphas[3] = {0.5f, 1.0f, 0.0f};
  uint16_t px[12];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) px[4 * i + k] = cycles_float_to_half(0.25f * float(k + 1) * alphas[i]);
    px[4 * i + 3] = cycles_float_to_half(alphas[i]);
  }
  uint16_t in[12];
  std::copy(px, px + 12, in);
  halves_to_scene_linear(config, "Filmic Log", px, 3, 4);
  for (int i = 0; i < 3; ++i) {
    const float a = cycles_half_to_float(in[4 * i + 3]);
    EXPECT_EQ(px[4 * i + 3], in[4 * i + 3]) << i;
    for (int k = 0; k < 3; ++k) {
      const float c = cycles_half_to_float(in[4 * i + k]);
      const float expected = a > 0 && a != 1 ? filmic_log(c / a) * a : filmic_log(c);
      EXPECT_NEAR(cycles_half_to_float(px[4 * i + k]), expected, expected * 2e-3f) << i << " " << k;
    }
  }
}

}  // namespace lt
