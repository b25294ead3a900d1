#include "shading/sky.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cstring>
#include <map>
#include <mutex>

#include "core/error.h"
#include "shading/nodes_math.h"

namespace lt {
namespace sky {

namespace {

// The atmosphere of Blender's intern/sky/source/sky_nishita.cpp (its data, in metres and nm).
constexpr float kRayleighScale = 8e3f;  // scale heights
constexpr float kMieScale = 1.2e3f;
constexpr float kMieCoeff = 2e-5f;  // Mie scattering coefficient (1/m); extinction is 1.11 times it
constexpr float kMieG = 0.76f;
constexpr float kEarthRadius = 6360e3f;
constexpr float kAtmosphereRadius = 6420e3f;
constexpr int kSteps = 32;        // segments of the view ray
constexpr int kWavelengths = 21;  // 380 nm to 780 nm
constexpr float kStepLambda = 20.0f;
// Sun irradiance at the top of the atmosphere (W m^-2 nm^-1), Rayleigh scattering and ozone
// absorption coefficients (1/m), per wavelength.
constexpr float kIrradiance[kWavelengths] = {1.45756829855592995315f, 1.56596305559738380175f, 1.65148449067670455293f,
                                             1.71496242737209314555f, 1.75797983805020541226f, 1.78256407885924539336f,
                                             1.79095108475838560302f, 1.78541550133410664714f, 1.76815554864306845317f,
                                             1.74122069647250410362f, 1.70647127164943679389f, 1.66556087452739887134f,
                                             1.61993437242451854274f, 1.57083597368892080581f, 1.51932335059305478886f,
                                             1.46628494965214395407f, 1.41245852740172450623f, 1.35844961970384092709f,
                                             1.30474913844739281998f, 1.25174963272610817455f, 1.19975998755420620867f};
constexpr float kRayleighCoeff[kWavelengths] = {
    0.00005424820087636473f, 0.00004418549866505454f, 0.00003635151910165377f, 0.00003017929012024763f,
    0.00002526320226989157f, 0.00002130859310621843f, 0.00001809838025320633f, 0.00001547057129129042f,
    0.00001330284977336850f, 0.00001150184784075764f, 0.00000999557429990163f, 0.00000872799973630707f,
    0.00000765513700977967f, 0.00000674217203751443f, 0.00000596134125832052f, 0.00000529034598065810f,
    0.00000471115687557433f, 0.00000420910481110487f, 0.00000377218381260133f, 0.00000339051255477280f,
    0.00000305591531679811f};
constexpr float kOzoneCoeff[kWavelengths] = {0.00000000325126849861f, 0.00000000585395365047f, 0.00000001977191155085f,
                                             0.00000007309568762914f, 0.00000020084561514287f, 0.00000040383958096161f,
                                             0.00000063551335912363f, 0.00000096707041180970f, 0.00000154797400424410f,
                                             0.00000209038647223331f, 0.00000246128056164565f, 0.00000273551299461512f,
                                             0.00000215125863128643f, 0.00000159051840791988f, 0.00000112356197979857f,
                                             0.00000073527551487574f, 0.00000046450130357806f, 0.00000033096079921048f,
                                             0.00000022512612292678f, 0.00000014879129266490f, 0.00000016828623364192f};
// CIE 1931 colour matching functions at the same wavelengths.
constexpr float kCmf[kWavelengths][3] = {
    {0.00136800000f, 0.00003900000f, 0.00645000100f}, {0.01431000000f, 0.00039600000f, 0.06785001000f},
    {0.13438000000f, 0.00400000000f, 0.64560000000f}, {0.34828000000f, 0.02300000000f, 1.74706000000f},
    {0.29080000000f, 0.06000000000f, 1.66920000000f}, {0.09564000000f, 0.13902000000f, 0.81295010000f},
    {0.00490000000f, 0.32300000000f, 0.27200000000f}, {0.06327000000f, 0.71000000000f, 0.07824999000f},
    {0.29040000000f, 0.95400000000f, 0.02030000000f}, {0.59450000000f, 0.99500000000f, 0.00390000000f},
    {0.91630000000f, 0.87000000000f, 0.00165000100f}, {1.06220000000f, 0.63100000000f, 0.00080000000f},
    {0.85444990000f, 0.38100000000f, 0.00019000000f}, {0.44790000000f, 0.17500000000f, 0.00002000000f},
    {0.16490000000f, 0.06100000000f, 0.00000000000f}, {0.04677000000f, 0.01700000000f, 0.00000000000f},
    {0.01135916000f, 0.00410200000f, 0.00000000000f}, {0.00289932700f, 0.00104700000f, 0.00000000000f},
    {0.00069007860f, 0.00024920000f, 0.00000000000f}, {0.00016615050f, 0.00006000000f, 0.00000000000f},
    {0.00004150994f, 0.00001499000f, 0.00000000000f}};
// Optical depth toward the sun by 8-point Gauss-Laguerre quadrature over the ray to the top of the
// atmosphere (nodes x_i / 25, weights w_i e^x_i / 25, as sky_nishita.cpp derives them).
constexpr int kQuadrature = 8;
constexpr float kQuadNodes[kQuadrature] = {0.006811185292f, 0.03614807107f, 0.09004346519f, 0.1706680068f,
                                           0.2818362161f,   0.4303406404f,  0.6296271457f,  0.9145252695f};
constexpr float kQuadWeights[kQuadrature] = {0.01750893642f, 0.04135477391f, 0.06678839063f, 0.09507698807f,
                                             0.1283416365f,  0.1707430204f,  0.2327233347f,  0.3562490486f};

Vec3 geographical(float lat, float lon) {
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

Vec3 to_xyz(const float* spectrum) {
  Vec3 xyz(0.0f);
  for (int i = 0; i < kWavelengths; ++i) xyz += Vec3(kCmf[i][0], kCmf[i][1], kCmf[i][2]) * spectrum[i];
  return xyz * kStepLambda;
}

// Density factors at a height above sea level: Rayleigh, Mie, ozone (a tent from 10 to 40 km).
Vec3 densities(float h) {
  float ozone = 0.0f;
  if (h >= 10000.0f && h < 25000.0f)
    ozone = 1.0f / 15000.0f * h - 2.0f / 3.0f;
  else if (h >= 25000.0f && h < 40000.0f)
    ozone = -(1.0f / 15000.0f * h - 8.0f / 3.0f);
  return {std::exp(-h / kRayleighScale), std::exp(-h / kMieScale), ozone};
}

float rayleigh_phase(float mu) { return 3.0f / (16.0f * kPi) * (1.0f + mu * mu); }

// Cornette-Shanks.
float mie_phase(float mu) {
  const float g2 = kMieG * kMieG;
  return (3.0f * (1.0f - g2) * (1.0f + mu * mu)) /
         (8.0f * kPi * (2.0f + g2) * std::pow(1.0f + g2 - 2.0f * kMieG * mu, 1.5f));
}

// Whether a ray from p toward d meets the ground.
bool hits_ground(const Vec3& p, const Vec3& d) {
  if (d.z >= 0) return false;
  const float b = -2.0f * dot(d, -p), c = dot(p, p) - kEarthRadius * kEarthRadius;
  return b * b - 4.0f * c >= 0.0f;
}

// Where a ray from p (inside the atmosphere) toward d leaves it.
Vec3 leave_atmosphere(const Vec3& p, const Vec3& d) {
  const float b = -2.0f * dot(d, -p), c = dot(p, p) - kAtmosphereRadius * kAtmosphereRadius;
  const float t = (-b + std::sqrt(b * b - 4.0f * c)) / 2.0f;
  return p + d * t;
}

// Optical depth factors (Rayleigh, Mie, ozone) from p to the top of the atmosphere along d.
Vec3 optical_depth(const Vec3& p, const Vec3& d) {
  const float span = length(leave_atmosphere(p, d) - p);
  const Vec3 segment = d * span;
  Vec3 depth(0.0f);
  for (int i = 0; i < kQuadrature; ++i)
    depth += densities(length(p + segment * kQuadNodes[i]) - kEarthRadius) * kQuadWeights[i];
  return depth * span;
}

// Single scattering along the view ray from p toward d, the sun toward s (midpoint rule, kSteps).
void single_scattering(const Vec3& d, const Vec3& s, const Vec3& p0, const Vec3& scale, float* spectrum) {
  const float step = length(leave_atmosphere(p0, d) - p0) / kSteps;
  const Vec3 segment = d * step;
  for (int i = 0; i < kWavelengths; ++i) spectrum[i] = 0.0f;
  const float mu = dot(d, s);
  const float ray_phase = rayleigh_phase(mu), mie = mie_phase(mu);
  Vec3 view_depth(0.0f);
  Vec3 p = p0 + segment * 0.5f;
  for (int k = 0; k < kSteps; ++k) {
    const Vec3 density = scale * densities(length(p) - kEarthRadius);
    view_depth += density * step;
    if (!hits_ground(p, s)) {
      const Vec3 depth = view_depth + scale * optical_depth(p, s);
      for (int i = 0; i < kWavelengths; ++i) {
        const float tau = depth.x * kRayleighCoeff[i] + depth.y * (1.11f * kMieCoeff) + depth.z * kOzoneCoeff[i];
        const float scattering = ray_phase * (density.x * kRayleighCoeff[i]) + mie * (density.y * kMieCoeff);
        spectrum[i] += std::exp(-tau) * scattering * kIrradiance[i] * step;
      }
    }
    p += segment;
  }
}

// The sun seen from the altitude through the air and dust along d, per unit solid angle of its disc.
Vec3 sun_xyz(const Vec3& d, float altitude, float air, float dust, float solid_angle) {
  const Vec3 depth = optical_depth(Vec3(0, 0, kEarthRadius + altitude), d);
  float spectrum[kWavelengths];
  for (int i = 0; i < kWavelengths; ++i) {
    const float tau = kRayleighCoeff[i] * depth.x * air + 1.11f * kMieCoeff * depth.y * dust;
    spectrum[i] = kIrradiance[i] * std::exp(-tau) / solid_angle;
  }
  return to_xyz(spectrum);
}

uint32_t float_bits(float f) {
  uint32_t w;
  std::memcpy(&w, &f, sizeof w);
  return w;
}

// Computed skies by their settings, shared while a program holds one (viewport edits and several
// programs with one sky compute it once).
std::shared_ptr<const std::vector<float>> cached_texture(float elevation, float altitude, float air, float dust,
                                                         float ozone) {
  static std::mutex mutex;
  static std::map<std::array<uint32_t, 5>, std::weak_ptr<const std::vector<float>>> cache;
  const std::array<uint32_t, 5> key = {float_bits(elevation), float_bits(altitude), float_bits(air), float_bits(dust),
                                       float_bits(ozone)};
  std::lock_guard<std::mutex> lock(mutex);
  if (auto hit = cache[key].lock()) return hit;
  for (auto it = cache.begin(); it != cache.end();) it = it->second.expired() ? cache.erase(it) : std::next(it);
  auto table = std::make_shared<const std::vector<float>>(nishita_texture(elevation, altitude, air, dust, ozone));
  cache[key] = table;
  return table;
}

// Nishita table layout (after the pool's count word).
constexpr int kBottom = 0, kTop = 3, kElevation = 6, kRotation = 7, kDiameter = 8, kIntensity = 9, kTexels = 10;
// Preetham: sun phi, theta, zenith x y z (radiance), then the Perez coefficients of Y, x and y.
constexpr int kPhi = 0, kTheta = 1, kZenith = 2, kPerez = 5, kPreethamSize = 5 + 3 * 5;

// Cycles' CPU image lookup, linear with Extend, of the Nishita table (kernel/device/cpu/image.h).
Vec3 texture_lookup(const float* texels, float x, float y) {
  const float fx = x * kNishitaWidth - 0.5f, fy = y * kNishitaHeight - 0.5f;
  const float x0f = std::floor(fx), y0f = std::floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  const int x0 = int(x0f), y0 = int(y0f);
  auto at = [&](int ix, int iy) {
    ix = clamp(ix, 0, kNishitaWidth - 1);
    iy = clamp(iy, 0, kNishitaHeight - 1);
    const float* t = texels + 3 * (size_t(iy) * kNishitaWidth + ix);
    return Vec3(t[0], t[1], t[2]);
  };
  return (at(x0, y0) * (1 - tx) + at(x0 + 1, y0) * tx) * (1 - ty) +
         (at(x0, y0 + 1) * (1 - tx) + at(x0 + 1, y0 + 1) * tx) * ty;
}

Vec3 rgb_clamped(const Vec3& xyz) { return vmax(xyz_to_rgb(xyz), Vec3(0.0f)); }

Vec3 nishita(const float* t, const Vec3& dir) {
  const float elevation = t[kElevation], rotation = t[kRotation], diameter = t[kDiameter];
  const float theta = std::acos(clamp(dir.z, -1.0f, 1.0f)), phi = std::atan2(dir.x, dir.y);
  const float x_of_phi = [&] {
    const float x = (phi + kPi + rotation) / (2 * kPi);
    return x > 1.0f ? x - 1.0f : x;
  }();
  Vec3 xyz(0.0f);
  if (dir.z >= 0.0f) {
    const Vec3 sun = geographical(elevation, rotation + kPi / 2);
    const float angle = 2.0f * std::atan2(length(dir - sun), length(dir + sun));  // Cycles' precise_angle
    const float half = diameter / 2.0f, dir_elevation = kPi / 2 - theta;
    if (diameter >= 0.0f && angle < half) {
      const Vec3 bottom(t[kBottom], t[kBottom + 1], t[kBottom + 2]), top(t[kTop], t[kTop + 1], t[kTop + 2]);
      if (elevation + half > 0.0f) {
        // Interpolated between the disc's bottom and top (its visible part when it sets).
        const float y = elevation - half > 0.0f ? (dir_elevation - elevation) / diameter + 0.5f
                                                : dir_elevation / (elevation + half);
        xyz = (bottom + (top - bottom) * y) * t[kIntensity];
      }
      const float r = angle / half;
      xyz *= 1.0f - 0.6f * (1.0f - std::sqrt(1.0f - r * r));  // limb darkening
    } else {
      // Rows are denser toward the horizon: y = sqrt(elevation / (pi/2)).
      xyz = texture_lookup(t + kTexels, x_of_phi, std::sqrt(std::max(dir_elevation / (kPi / 2), 0.0f)));
    }
  } else if (dir.z >= -0.4f) {
    // Below the horizon, the horizon's colour fading to black at z = -0.4.
    const float fade = 1.0f + dir.z * 2.5f;
    xyz = texture_lookup(t + kTexels, x_of_phi, -0.5f) * (fade * fade * fade);
  }
  return rgb_clamped(xyz);
}

float perez(const float* lam, float theta, float gamma) {
  const float cg = std::cos(gamma);
  return (1.0f + lam[0] * std::exp(lam[1] / std::cos(theta))) *
         (1.0f + lam[2] * std::exp(lam[3] * gamma) + lam[4] * cg * cg);
}

Vec3 preetham(const float* t, const Vec3& dir) {
  float theta = std::acos(clamp(dir.z, -1.0f, 1.0f));
  const float phi = std::atan2(dir.x, dir.y);
  const float sun_theta = t[kTheta], sun_phi = t[kPhi];
  const float cos_gamma =
      std::sin(theta) * std::sin(sun_theta) * std::cos(sun_phi - phi) + std::cos(theta) * std::cos(sun_theta);
  const float gamma = std::acos(clamp(cos_gamma, -1.0f, 1.0f));
  theta = std::min(theta, kPi / 2 - 0.001f);
  const float x = t[kZenith + 1] * perez(t + kPerez + 5, theta, gamma);
  const float y = t[kZenith + 2] * perez(t + kPerez + 10, theta, gamma);
  const float Y = t[kZenith] * perez(t + kPerez, theta, gamma);
  // xyY to XYZ (Cycles' xyY_to_xyz).
  const float X = y != 0.0f ? x / y * Y : 0.0f;
  const float Z = y != 0.0f && Y != 0.0f ? (1.0f - x - y) / y * Y : 0.0f;
  return rgb_clamped(Vec3(X, Y, Z));
}

// Cycles' sky_texture_precompute_preetham: the zenith's xyY and the Perez coefficients for a
// turbidity, each zenith value divided by its Perez function at the zenith.
std::vector<float> preetham_table(const Vec3& sun, float turbidity) {
  std::vector<float> t(kPreethamSize);
  const float theta = std::acos(sun.z), phi = std::atan2(sun.x, sun.y);
  t[kTheta] = theta;
  t[kPhi] = phi;
  const float T = turbidity, T2 = T * T, th2 = theta * theta, th3 = th2 * theta;
  const float chi = (4.0f / 9.0f - T / 120.0f) * (kPi - 2.0f * theta);
  t[kZenith] = ((4.0453f * T - 4.9710f) * std::tan(chi) - 0.2155f * T + 2.4192f) * 0.06f;
  t[kZenith + 1] = (0.00166f * th3 - 0.00375f * th2 + 0.00209f * theta) * T2 +
                   (-0.02903f * th3 + 0.06377f * th2 - 0.03202f * theta + 0.00394f) * T +
                   (0.11693f * th3 - 0.21196f * th2 + 0.06052f * theta + 0.25886f);
  t[kZenith + 2] = (0.00275f * th3 - 0.00610f * th2 + 0.00317f * theta) * T2 +
                   (-0.04214f * th3 + 0.08970f * th2 - 0.04153f * theta + 0.00516f) * T +
                   (0.15346f * th3 - 0.26756f * th2 + 0.06670f * theta + 0.26688f);
  const float perez_coeffs[3][5][2] = {
      {{0.1787f, -1.4630f}, {-0.3554f, 0.4275f}, {-0.0227f, 5.3251f}, {0.1206f, -2.5771f}, {-0.0670f, 0.3703f}},
      {{-0.0193f, -0.2592f}, {-0.0665f, 0.0008f}, {-0.0004f, 0.2125f}, {-0.0641f, -0.8989f}, {-0.0033f, 0.0452f}},
      {{-0.0167f, -0.2608f}, {-0.0950f, 0.0092f}, {-0.0079f, 0.2102f}, {-0.0441f, -1.6537f}, {-0.0109f, 0.0529f}}};
  for (int c = 0; c < 3; ++c) {
    float* lam = t.data() + kPerez + 5 * c;
    for (int i = 0; i < 5; ++i) lam[i] = perez_coeffs[c][i][0] * T + perez_coeffs[c][i][1];
    t[kZenith + c] /= perez(lam, 0.0f, theta);
  }
  return t;
}

}  // namespace

std::vector<float> nishita_texture(float sun_elevation, float altitude, float air, float dust, float ozone) {
  std::vector<float> px(size_t(kNishitaWidth) * kNishitaHeight * 3);
  const Vec3 camera(0, 0, kEarthRadius + altitude), sun = geographical(sun_elevation, 0.0f);
  const Vec3 scale(air, dust, ozone);
  const float half_row = kPi / 2 / kNishitaHeight / 2.0f, column = 2 * kPi / kNishitaWidth;
  tbb::parallel_for(0, kNishitaHeight, [&](int y) {
    const float r = float(y) / kNishitaHeight;
    const float latitude = (kPi / 2 + half_row) * (r * r);
    float spectrum[kWavelengths];
    for (int x = 0; x < kNishitaWidth / 2; ++x) {
      single_scattering(geographical(latitude, column * x - kPi), sun, camera, scale, spectrum);
      const Vec3 xyz = to_xyz(spectrum);
      // The sky is symmetric about the sun's meridian: column x and its mirror.
      for (int c : {x, kNishitaWidth - 1 - x}) {
        float* p = px.data() + 3 * (size_t(y) * kNishitaWidth + c);
        p[0] = xyz.x;
        p[1] = xyz.y;
        p[2] = xyz.z;
      }
    }
  });
  return px;
}

void nishita_sun(float sun_elevation, float angular_diameter, float altitude, float air, float dust, Vec3* bottom,
                 Vec3* top) {
  const float half = angular_diameter / 2.0f;
  const float solid_angle = 2 * kPi * (1.0f - std::cos(half));
  *bottom = sun_xyz(geographical(std::max(sun_elevation - half, 0.0f), 0.0f), altitude, air, dust, solid_angle);
  *top = sun_xyz(geographical(std::max(sun_elevation + half, 0.0f), 0.0f), altitude, air, dust, solid_angle);
}

std::vector<float> make_table(uint32_t type, const float s[kSettings]) {
  for (int i = 0; i < kSettings; ++i)
    if (!std::isfinite(s[i])) throw InvalidArgument("Sky Texture setting " + std::to_string(i) + " is not finite");
  if (type != kSkyNishita) {
    const Vec3 d(s[0], s[1], s[2]);
    const float l = length(d);
    // Cycles takes the sun direction as given; a zero one points the sun at the zenith.
    return preetham_table(l > 0 ? d * (1.0f / l) : Vec3(0, 0, 1), s[3]);
  }
  // Cycles' SkyTextureNode::compile: the sun size at least 0.0005 rad, the altitude within 1 m and
  // 60 km, the rotation in [0, 2 pi) then reversed.
  const float size = std::max(s[1], 0.0005f), elevation = s[3], altitude = clamp(s[5], 1.0f, 59999.0f);
  float rotation = std::fmod(s[4], 2 * kPi);
  if (rotation < 0.0f) rotation += 2 * kPi;
  rotation = 2 * kPi - rotation;
  Vec3 bottom, top;
  nishita_sun(elevation, size, altitude, s[6], s[7], &bottom, &top);
  const auto texels = cached_texture(elevation, altitude, s[6], s[7], s[8]);
  std::vector<float> t(kTexels);
  for (int c = 0; c < 3; ++c) {
    t[kBottom + c] = bottom[c];
    t[kTop + c] = top[c];
  }
  t[kElevation] = elevation;
  t[kRotation] = rotation;
  t[kDiameter] = s[0] != 0.0f ? size : -1.0f;
  t[kIntensity] = s[2];
  t.insert(t.end(), texels->begin(), texels->end());
  for (float& v : t)
    if (!std::isfinite(v)) v = 0.0f;  // densities far beyond Blender's range can overflow
  return t;
}

Vec3 radiance(uint32_t type, const float* table, const Vec3& dir) {
  return type == kSkyNishita ? nishita(table, dir) : preetham(table, dir);
}

bool sun_disc(uint32_t type, const float* table, Vec3* dir, float* half_angle) {
  if (type != kSkyNishita || !(table[kDiameter] >= 0.0f)) return false;
  *dir = geographical(table[kElevation], table[kRotation] + kPi / 2);
  *half_angle = table[kDiameter] / 2.0f;
  return true;
}

}  // namespace sky
}  // namespace lt
