// The Sky Texture node (textures family, kOpTexSky) as Cycles 3.4 renders it: the Nishita single
// scattering sky (Nishita et al. 1993, Blender's intern/sky/source/sky_nishita.cpp) precomputed into
// a 512 x 128 table and the sun disc's two colours, read as kernel/svm/sky.h's sky_radiance_nishita;
// Preetham's analytic sky (Preetham, Shirley and Smits 1999; Cycles' sky_texture_precompute_preetham
// and sky_radiance_preetham). The precompute runs when a program is loaded (Program's constructor,
// prepare_textures_family), once per distinct parameter set while a table of that set is alive.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/math.h"

namespace lt {
namespace sky {

// Cycles' NodeSkyType order.
enum SkyType : uint32_t { kSkyPreetham = 0, kSkyHosek = 1, kSkyNishita = 2 };

constexpr int kNishitaWidth = 512, kNishitaHeight = 128;  // Cycles' SkyLoader

// The Nishita sky's XYZ radiance for a sun at `sun_elevation` (radians) and longitude 0, row by row
// from the horizon (latitude (pi/2 + half a row) (y / height)^2) and column x at longitude
// 2 pi x / width - pi: kNishitaWidth x kNishitaHeight x 3 floats (SKY_nishita_skymodel_precompute_texture).
std::vector<float> nishita_texture(float sun_elevation, float altitude, float air, float dust, float ozone);
// The sun disc's XYZ radiance at its bottom and top edge (SKY_nishita_skymodel_precompute_sun).
void nishita_sun(float sun_elevation, float angular_diameter, float altitude, float air, float dust, Vec3* bottom,
                 Vec3* top);

// The node's settings as the instruction's params carry them (kOpTexSky: type, then these as float
// bits). Nishita: sun disc (0 or 1), sun size, sun intensity, sun elevation, sun rotation, altitude,
// air, dust, ozone. Preetham: sun direction x, y, z, turbidity, then zeros.
constexpr int kSettings = 9;

// The table the loader appends to the program's pool for one Sky Texture instruction (the floats
// after the pool's count word). Throws InvalidArgument on a setting that is not finite.
std::vector<float> make_table(uint32_t type, const float settings[kSettings]);

// The node's colour (linear RGB, clamped to >= 0) for the vector `dir` (not normalised, as Cycles
// reads it), from a table make_table built.
Vec3 radiance(uint32_t type, const float* table, const Vec3& dir);

// A Nishita table's sun disc: its direction and half its angular diameter; false when it has none.
bool sun_disc(uint32_t type, const float* table, Vec3* dir, float* half_angle);

}  // namespace sky
}  // namespace lt
