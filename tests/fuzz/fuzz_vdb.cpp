// libFuzzer target: the VDB loader. The input is written to a file and loaded as a Volume object
// through the C ABI (lt_scene_add_volume_grid: OpenVDB's reader, Lantern's checks, the NanoVDB
// conversion and the majorant grid); a grid that loads is rendered (2x2 pixels, one sample, by
// tracking and by ray marching) with the camera aimed at its bounds, moving over the shutter for
// inputs of odd size. Every file must either load or be refused with LT_ERROR_IO and a message.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "io/vdb.h"
#include "lantern/lantern.h"

namespace {

std::string g_path;

void fail(const char* what) {
  std::fprintf(stderr, "%s: %s\n", what, lt_last_error());
  std::abort();
}

void render(lt_scene* scene, int estimator) {
  lt_render_settings s;
  lt_render_settings_default(&s);
  s.width = s.height = 2;
  s.samples = 1;
  s.threads = 1;
  s.integrator = LT_INTEGRATOR_VOLPATH;
  s.volume_estimator = estimator;
  s.volume_bounces = 2;
  lt_render* job = nullptr;
  if (lt_render_start(scene, &s, &job) != LT_OK) fail("render start");
  lt_render_wait(job);
  float px[2 * 2 * 4];
  if (lt_render_read_pass(job, LT_PASS_COMBINED, px, 16) != LT_OK) fail("read pass");
  for (float v : px)
    if (!std::isfinite(v)) {
      std::fprintf(stderr, "non-finite pixel %g\n", v);
      std::abort();
    }
  lt_render_destroy(job);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char dir[] = "/tmp/lantern_fuzz_vdb_XXXXXX";
  if (!mkdtemp(dir)) std::abort();
  g_path = std::string(dir) + "/in.vdb";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FILE* f = std::fopen(g_path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();

  lt_scene* scene = nullptr;
  lt_scene_create(&scene);
  const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  lt_volume_desc d = {};
  d.node = LT_VOLUME_PRINCIPLED;
  d.color[0] = d.color[1] = d.color[2] = 0.8f;
  d.density = 1;
  d.absorption_color[0] = d.absorption_color[1] = d.absorption_color[2] = 0.5f;
  int id = -1;
  const int status = lt_scene_add_volume_grid(scene, g_path.c_str(), "density", identity, 0, 0.001f, 0.0f, &d, 1, &id);
  if (status != LT_OK && status != LT_ERROR_IO && status != LT_ERROR_OUT_OF_MEMORY) fail("unexpected status");
  if (status != LT_OK && !*lt_last_error()) fail("status without a message");
  if (status == LT_OK) {
    // Aim the camera at the grid's bounds (world = object space here), from outside them.
    lt::GridData g = lt::load_density_grid(g_path, "density");
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = hi[a] = g.index_to_object.m[a * 4 + 3];
      for (int c = 0; c < 3; ++c) {
        const float e = g.index_to_object.m[a * 4 + c];
        lo[a] += std::min(e * float(g.index_min[c]), e * float(g.index_max[c]));
        hi[a] += std::max(e * float(g.index_min[c]), e * float(g.index_max[c]));
      }
    }
    const float cx = 0.5f * (lo[0] + hi[0]), cy = 0.5f * (lo[1] + hi[1]), cz = 0.5f * (lo[2] + hi[2]);
    const float extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-3f});
    lt_camera_desc cam = {};
    cam.type = LT_CAMERA_ORTHOGRAPHIC;  // looks down -Z from above the bounds
    const float xf[12] = {1, 0, 0, cx, 0, 1, 0, cy, 0, 0, 1, hi[2] + extent};
    for (int k = 0; k < 12; ++k) cam.transform[k] = xf[k];
    cam.focal_length = 50;
    cam.sensor_width = 36;
    cam.sensor_height = 24;
    cam.ortho_scale = extent;
    cam.clip_start = 0;
    cam.clip_end = 1e30f;
    cam.pixel_aspect = 1;
    lt_world_desc world = {{1, 1, 1}, 1, -1, 0, LT_VISIBLE_ALL};
    // Inputs of odd size also move the grid over the shutter (ABI 26), by its extent along x.
    const float steps[36] = {1, 0, 0, -extent, 0, 1, 0, 0, 0, 0,      1, 0, 1, 0, 0, 0, 0, 1,
                             0, 0, 0, 0,       1, 0, 1, 0, 0, extent, 0, 1, 0, 0, 0, 0, 1, 0};
    if (size % 2 == 1 && std::isfinite(extent) && lt_scene_set_volume_grid_motion(scene, id, steps, 3) != LT_OK)
      fail("volume motion");
    if (std::isfinite(cx + cy + cz + extent) && lt_scene_set_camera(scene, &cam) == LT_OK &&
        lt_scene_set_world(scene, &world) == LT_OK) {
      if (lt_scene_commit(scene) != LT_OK) fail("commit");
      render(scene, LT_VOLUME_TRACKING);
      render(scene, LT_VOLUME_RAY_MARCHING);
    }
  }
  lt_scene_destroy(scene);
  return 0;
}
