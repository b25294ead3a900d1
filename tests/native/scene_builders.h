// Scene builders for tests and benchmarks: meshes (boxes, planes, icospheres, UV spheres),
// transforms, materials, cameras, lights and a blocking render helper, all through the C ABI
// (lantern.h) only, so that anything built here is exactly what the add-on could build.
//
// Failures of ABI calls throw std::runtime_error carrying lt_last_error(); GoogleTest reports an
// escaped exception as a test failure, and benchmarks stop with the message.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lantern/lantern.h"
#include "program_builder.h"

namespace lt_test {

constexpr double kPi = 3.14159265358979323846;
// Statistical checks allow this many standard errors (a false alarm about once in 1.7 million).
constexpr double kSigmas = 5.0;

struct V3 {
  float x = 0, y = 0, z = 0;
};

// Row-major 3x4 object-to-world transform, the ABI's layout.
using Xform = std::array<float, 12>;
Xform identity();
Xform translate(V3 t);
Xform scale(V3 s);
Xform rotate(V3 axis, float radians);
Xform compose(const Xform& a, const Xform& b);  // a * b: b applied first
// Frame at `eye` whose local -Z points at `target` and whose +Y is as close to `up` as possible
// (cameras, spot, sun and area lights all look down their local -Z).
Xform look_at(V3 eye, V3 target, V3 up = {0, 0, 1});
V3 apply_point(const Xform& m, V3 p);

// Triangle soup with shared vertices; corner_normals empty or 9 floats per triangle.
struct MeshData {
  std::vector<float> positions;
  std::vector<int> triangles;
  std::vector<float> corner_normals;
  int vertex_count() const { return int(positions.size() / 3); }
  int triangle_count() const { return int(triangles.size() / 3); }
  lt_mesh_desc desc() const;  // points into this object: keep it alive during the ABI call
};

MeshData box(V3 lo, V3 hi, bool open_top = false);   // outward winding; open_top drops +Z face
MeshData plane(float size_x, float size_y);          // z = 0, centred, normal +Z
MeshData icosphere(float radius, int subdivisions);  // vertices on the sphere, outward winding
MeshData uv_sphere(float radius, int segments, int rings, bool smooth_normals = false);
void flip_winding(MeshData& m);                     // makes normals face the other way
void transform_mesh(MeshData& m, const Xform& xf);  // bakes a transform into positions
void append(MeshData& dst, const MeshData& src);

// RAII handles.
struct SceneDeleter {
  void operator()(lt_scene* s) const { lt_scene_destroy(s); }
};
struct RenderDeleter {
  void operator()(lt_render* r) const { lt_render_destroy(r); }
};
using ScenePtr = std::unique_ptr<lt_scene, SceneDeleter>;
using RenderPtr = std::unique_ptr<lt_render, RenderDeleter>;
ScenePtr new_scene();

// Throws std::runtime_error("<what>: <lt_last_error()>") unless status == LT_OK.
void check(int status, const char* what);

int add_material(lt_scene* s, const ShaderCode& p);
int add_diffuse(lt_scene* s, V3 color, float roughness = 0);
int add_glass(lt_scene* s, V3 color, float roughness, float ior);
int add_emission(lt_scene* s, V3 color, float strength);
int add_glossy(lt_scene* s, V3 color, float roughness);  // GGX
int add_mesh(lt_scene* s, const MeshData& m);
int add_instance(lt_scene* s, int mesh, int material, const Xform& xf = identity(),
                 unsigned visibility = LT_VISIBLE_ALL, int lightgroup = 0,  // lightgroup: k + 1, 0 none
                 bool shadow_catcher = false);
// add_mesh + add_instance.
int add_object(lt_scene* s, const MeshData& m, int material, const Xform& xf = identity(),
               unsigned visibility = LT_VISIBLE_ALL, bool shadow_catcher = false);

lt_camera_desc perspective_camera(const Xform& xf, float focal_mm = 50, float sensor_mm = 36);
lt_camera_desc orthographic_camera(const Xform& xf, float ortho_scale);
// Blender's defaults for the panorama settings (Cycles' camera properties), of the given type.
lt_camera_desc panorama_camera(const Xform& xf, int panorama_type);
// Depth of field on a camera: Blender's defaults (a round aperture, ratio 1) at this F-stop.
lt_camera_desc with_dof(lt_camera_desc c, float focus_distance, float fstop, int blades = 0, float rotation = 0,
                        float ratio = 1);
void set_camera(lt_scene* s, const lt_camera_desc& c);

lt_world_desc world(V3 color, float strength);
void set_world(lt_scene* s, V3 color, float strength);

// color: Blender's colour x energy. transform: the light looks down its local -Z.
lt_light_desc light(int type, V3 color, const Xform& xf);
lt_light_desc point_light(V3 position, float watts);
lt_light_desc spot_light(V3 position, V3 target, float watts, float size_radians, float blend);
lt_light_desc sun_light(V3 direction_of_travel, float strength, float angle_radians = 0);
lt_light_desc area_light(int shape, float size_x, float size_y, const Xform& xf, float watts);
void add_light(lt_scene* s, const lt_light_desc& l);

// A volume node (LT_VOLUME_*) with a grey colour and anisotropy g.
lt_volume_desc volume(int node, float density, float color = 1, float g = 0);
// A material whose only output is a volume: a Transparent surface for PATH, an invisible boundary
// for the integrators that render media.
int add_volume_material(lt_scene* s, const lt_volume_desc& d);
int add_volume_material(lt_scene* s, const lt_volume_desc* components, int count);  // their sum

// A committed scene that exercises most of the path tracer: diffuse, glossy, glass and emissive
// surfaces, an area light, a soft point light, a sun and the world; with fog, a fog box around the
// glossy sphere (the determinism tests and the ThreadSanitizer driver).
ScenePtr varied_scene(bool fog = false);
// A committed Cornell-like box: a 2 m room (white floor, ceiling and back wall, red left and green
// right walls, open towards the camera), a square area light under the ceiling, a tall and a short
// white block (the denoiser's tests and benchmark).
ScenePtr cornell_scene();

// Defaults with the given size, samples and seed.
lt_render_settings render_settings(int width, int height, int samples, unsigned seed = 0);
// The same with the volumetric path tracer.
lt_render_settings volpath_settings(int width, int height, int samples, unsigned seed = 1);

// Every pass of a finished (or cancelled) render, rows bottom to top as the ABI gives them.
struct Passes {
  int width = 0, height = 0;
  std::vector<float> combined, depth, normal, albedo, variance, sample_count;
  std::vector<float> noisy, denoising_normal, denoising_albedo, denoising_depth;
  // The light and data passes, from LT_PASS_DIFFUSE_DIRECT on.
  std::vector<float> more[LT_PASS_COUNT - LT_PASS_DIFFUSE_DIRECT];
  const std::vector<float>& pass(int p) const { return more[p - LT_PASS_DIFFUSE_DIRECT]; }
  lt_render_status status{};
  const float* rgba(int x, int y) const { return &combined[(size_t(y) * width + x) * 4]; }
  const float* var(int x, int y) const { return &variance[(size_t(y) * width + x) * 3]; }
  // Name of the first pass holding a NaN or Inf, or "" when every value is finite.
  std::string first_non_finite() const;
};
Passes read_passes(lt_render* r, int width, int height);
// Starts, waits, reads every pass and destroys the render.
Passes render(lt_scene* s, const lt_render_settings& settings);

// Mean of the pixel means of channel c over [x0, x1) x [y0, y1), and its standard error from the
// Variance pass: sqrt(sum of the pixel means' variances) / N (pixels are independent).
struct RegionStats {
  double mean = 0, standard_error = 0;
  int pixels = 0;
};
RegionStats region_stats(const Passes& p, int channel, int x0, int x1, int y0, int y1);
// Compares two renders per tile x tile pixels and RGB channel: one line for each tile whose means
// differ by more than z standard errors of their difference (each from its render's Variance
// pass, so for renders whose pixels are independent), "" when none does.
std::string differing_tiles(const Passes& a, const Passes& b, int tile, double z);

// A unique empty directory under $TMPDIR (or /tmp), removed with its files by the destructor.
struct TempDir {
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path;
};

}  // namespace lt_test
