// libFuzzer target: the C ABI's scene building. The input is decoded (abi_stream.h) into a
// sequence of lt_scene_* calls, commits and tiny renders (at most 8x8 pixels, 4 samples, one or
// two threads) on one scene; every call must either succeed or fail with a status and a message,
// and never crash, leak or hit undefined behaviour. Field order per operation is the order of the
// reads below; make_fuzz_seeds.cpp writes the same order.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "abi_stream.h"
#include "lantern/lantern.h"

namespace {

using lt_fuzz::Reader;

int small(Reader& r, int n) { return int(r.u8()) % n; }

// A status other than LT_OK must come with a message.
void check(int status) {
  if (status != LT_OK && (!lt_last_error() || !*lt_last_error())) {
    std::fprintf(stderr, "status %d without a message\n", status);
    std::abort();
  }
}

// A shader program: words, constants and a register count, as they come (the core validates).
struct ProgramData {
  std::vector<uint32_t> code;
  std::vector<float> constants;
  lt_shader_program desc;
};
ProgramData program(Reader& r) {
  ProgramData p;
  p.code.resize(r.u8());  // up to 255 words
  for (uint32_t& w : p.code) w = r.u32();
  p.constants.resize(size_t(small(r, lt_fuzz::kMaxConstants + 1)));
  r.floats(p.constants.data(), int(p.constants.size()));
  const int registers = int(r.u8()) * 4;
  p.desc = {p.code.data(), int(p.code.size()), p.constants.data(), int(p.constants.size()), registers};
  return p;
}

std::vector<lt_volume_desc> volume(Reader& r) {
  std::vector<lt_volume_desc> v(size_t(small(r, lt_fuzz::kMaxComponents + 1)));  // 0: refused
  for (lt_volume_desc& d : v) {
    d.node = r.i8();
    r.floats(d.color, 3);
    d.density = r.f32();
    r.floats(d.absorption_color, 3);
    d.anisotropy = r.f32();
    d.emission_strength = r.f32();
    r.floats(d.emission_color, 3);
    d.blackbody_intensity = r.f32();
    r.floats(d.blackbody_tint, 3);
    d.temperature = r.f32();
  }
  return v;
}

void render(lt_scene* scene, Reader& r) {
  lt_render_settings s;
  lt_render_settings_default(&s);
  s.width = 1 + small(r, lt_fuzz::kMaxResolution);
  s.height = 1 + small(r, lt_fuzz::kMaxResolution);
  if (r.u8() & 1)
    for (int& b : s.border) b = small(r, lt_fuzz::kMaxResolution + 1);
  s.samples = 1 + small(r, lt_fuzz::kMaxSamples);
  s.seed = r.u8();
  s.sample_offset = small(r, 4);
  s.integrator = small(r, LT_INTEGRATOR_COUNT + 1);  // the last: refused
  s.max_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.diffuse_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.glossy_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.transmission_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.transparent_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.clamp_direct = r.f32();
  s.clamp_indirect = r.f32();
  s.threads = 1 + small(r, 2);
  s.filter = small(r, 4);
  s.filter_width = r.f32();
  s.transparent_background = r.u8() & 1;
  s.max_camera_length = 1 + small(r, lt_fuzz::kMaxBounces);
  s.max_light_length = small(r, lt_fuzz::kMaxBounces + 1);
  s.mis_heuristic = small(r, 4);
  s.strategy_view_depth = small(r, 4);
  s.volume_bounces = small(r, lt_fuzz::kMaxBounces + 1);
  s.volume_estimator = small(r, 3);
  s.volume_step = r.f32();
  s.noise_target = r.f32();
  s.adaptive = r.u8() & 1;
  s.min_samples = 1 + small(r, 4);
  lt_render* job = nullptr;
  const int status = lt_render_start(scene, &s, &job);
  check(status);
  if (status != LT_OK) return;
  check(lt_render_wait(job));
  lt_render_status st;
  check(lt_render_poll(job, &st));
  if (st.state != LT_STATE_DONE) {
    std::fprintf(stderr, "render ended in state %d\n", st.state);
    std::abort();
  }
  const int w = s.border[1] > s.border[0] && s.border[3] > s.border[2] ? s.border[1] - s.border[0] : s.width;
  const int h = s.border[1] > s.border[0] && s.border[3] > s.border[2] ? s.border[3] - s.border[2] : s.height;
  for (int pass = 0; pass < LT_PASS_COUNT; ++pass) {
    std::vector<float> px(size_t(w) * h * size_t(lt_pass_channels(pass)));
    check(lt_render_read_pass(job, pass, px.data(), px.size()));
    // No NaN anywhere; no infinity but in Variance (the square of a finite float may not be one).
    for (float v : px)
      if (std::isnan(v) || (std::isinf(v) && pass != LT_PASS_VARIANCE)) {
        std::fprintf(stderr, "pass %d holds %g\n", pass, v);
        std::abort();
      }
  }
  int gw = 0, gh = 0;
  if (lt_render_read_strategy_grid(job, nullptr, 0, &gw, &gh) == LT_OK) {
    std::vector<float> grid(size_t(gw) * gh * 3);
    check(lt_render_read_strategy_grid(job, grid.data(), grid.size(), &gw, &gh));
  }
  lt_render_destroy(job);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Reader r(data, size);
  lt_scene* scene = nullptr;
  if (lt_scene_create(&scene) != LT_OK) std::abort();
  while (!r.done()) {
    const int op = r.u8() % lt_fuzz::kOpCount;
    int id = 0;
    switch (op) {
      case lt_fuzz::kAddImage: {
        lt_image_desc d{};  // the colour space strings stay NULL
        d.width = 1 + small(r, lt_fuzz::kMaxImageSide);
        d.height = 1 + small(r, lt_fuzz::kMaxImageSide);
        d.channels = r.i8();
        const int ch = d.channels == 1 || d.channels == 3 || d.channels == 4 ? d.channels : 1;
        std::vector<float> px(size_t(d.width) * d.height * ch);
        r.floats(px.data(), int(px.size()));
        d.pixels = px.data();
        d.srgb = r.u8() & 1;
        d.interpolation = r.i8();
        d.extension = r.i8();
        check(lt_scene_add_image(scene, &d, &id));
        break;
      }
      case lt_fuzz::kAddMaterial:
      case lt_fuzz::kSetMaterial: {
        const int material = op == lt_fuzz::kSetMaterial ? r.i8() : 0;
        ProgramData p = program(r);
        check(op == lt_fuzz::kSetMaterial ? lt_scene_set_material(scene, material, &p.desc)
                                          : lt_scene_add_material(scene, &p.desc, &id));
        break;
      }
      case lt_fuzz::kAddMesh: {
        const int nv = small(r, lt_fuzz::kMaxVertices + 1), nt = small(r, lt_fuzz::kMaxTriangles + 1);
        const uint8_t parts = r.u8();  // bit 0: normals, 1: UVs, 2: material slots
        std::vector<float> pos(size_t(nv) * 3), normals, uvs;
        std::vector<int> tris(size_t(nt) * 3), slots;
        r.floats(pos.data(), int(pos.size()));
        for (int& t : tris) t = r.i8();
        if (parts & 1) {
          normals.resize(size_t(nt) * 9);
          r.floats(normals.data(), int(normals.size()));
        }
        if (parts & 2) {
          uvs.resize(size_t(nt) * 6);
          r.floats(uvs.data(), int(uvs.size()));
        }
        if (parts & 4) {
          slots.resize(size_t(nt));
          for (int& s : slots) s = r.i8();
        }
        lt_mesh_desc d{pos.data(),
                       nv,
                       tris.data(),
                       nt,
                       (parts & 1) ? normals.data() : nullptr,
                       (parts & 2) ? uvs.data() : nullptr,
                       (parts & 4) ? slots.data() : nullptr};
        check(lt_scene_add_mesh(scene, &d, &id));
        break;
      }
      case lt_fuzz::kAddInstance: {
        lt_instance_desc d{};  // fields the input does not set (colour, attributes) stay zero
        d.mesh = r.i8();
        r.floats(d.transform, 12);
        std::vector<int> materials(size_t(small(r, lt_fuzz::kMaxSlots + 1)));
        for (int& m : materials) m = r.i8();
        d.materials = materials.data();
        d.material_count = int(materials.size());
        d.visibility = r.u8();
        check(lt_scene_add_instance(scene, &d, &id));
        break;
      }
      case lt_fuzz::kAddLight: {
        lt_light_desc d{};  // the light group the input does not set stays 0
        d.type = r.i8();
        r.floats(d.color, 3);
        r.floats(d.transform, 12);
        d.radius = r.f32();
        d.spot_size = r.f32();
        d.spot_blend = r.f32();
        d.shape = r.i8();
        d.size_x = r.f32();
        d.size_y = r.f32();
        d.angle = r.f32();
        d.visibility = r.u8();
        d.spread = r.f32();
        check(lt_scene_add_light(scene, &d));
        break;
      }
      case lt_fuzz::kSetCamera:
      case lt_fuzz::kSetCameraLens: {
        lt_camera_desc d{};
        d.type = r.i8();
        r.floats(d.transform, 12);
        d.focal_length = r.f32();
        d.sensor_width = r.f32();
        d.sensor_height = r.f32();
        d.sensor_fit = r.i8();
        d.ortho_scale = r.f32();
        d.shift_x = r.f32();
        d.shift_y = r.f32();
        d.clip_start = r.f32();
        d.clip_end = r.f32();
        d.pixel_aspect = r.f32();
        if (op == lt_fuzz::kSetCameraLens) {
          d.use_dof = r.u8() & 1;
          d.focus_distance = r.f32();
          d.aperture_fstop = r.f32();
          d.aperture_blades = r.i8();
          d.aperture_rotation = r.f32();
          d.aperture_ratio = r.f32();
          d.panorama_type = r.i8();
          d.fisheye_fov = r.f32();
          d.fisheye_lens = r.f32();
          d.latitude_min = r.f32();
          d.latitude_max = r.f32();
          d.longitude_min = r.f32();
          d.longitude_max = r.f32();
        }
        check(lt_scene_set_camera(scene, &d));
        break;
      }
      case lt_fuzz::kSetWorld: {
        lt_world_desc d;
        r.floats(d.color, 3);
        d.strength = r.f32();
        d.image = r.i8();
        d.rotation_z = r.f32();
        d.visibility = r.u8();
        check(lt_scene_set_world(scene, &d));
        break;
      }
      case lt_fuzz::kSetMaterialVolume: {
        const int material = r.i8();
        const int null_surface = r.u8() & 1;
        std::vector<lt_volume_desc> v = volume(r);
        check(
            lt_scene_set_material_volume(scene, material, v.empty() ? nullptr : v.data(), int(v.size()), null_surface));
        break;
      }
      case lt_fuzz::kSetWorldProgram: {
        // Resolutions past 64 are refused or slow: negative values stay, others wrap to 0-64 (0:
        // automatic, the Environment Texture's image size or 1024 x 512).
        const int8_t b = r.i8();
        const int resolution = b < 0 ? b : b % 65;
        const unsigned visibility = r.u8();
        ProgramData p = program(r);
        check(lt_scene_set_world_program(scene, &p.desc, resolution, visibility));
        break;
      }
      case lt_fuzz::kSetWorldVolume: {
        std::vector<lt_volume_desc> v = volume(r);
        check(lt_scene_set_world_volume(scene, v.empty() ? nullptr : v.data(), int(v.size())));
        break;
      }
      case lt_fuzz::kSetInstanceTransform: {
        const int instance = r.i8();
        float xf[12];
        r.floats(xf, 12);
        check(lt_scene_set_instance_transform(scene, instance, xf));
        break;
      }
      case lt_fuzz::kSetInstanceValues: {
        const int instance = r.i8();
        const unsigned visibility = r.u8();
        float color[4];
        r.floats(color, 4);
        const int pass_index = r.i8();
        const int count = r.i8() % 3;  // negative counts too
        std::vector<int> ids(2);
        std::vector<float> values(8);
        for (int& i : ids) i = r.i8();
        r.floats(values.data(), 8);
        check(lt_scene_set_instance_values(scene, instance, visibility, color, pass_index, ids.data(), values.data(),
                                           count));
        break;
      }
      case lt_fuzz::kSetInstanceMotion: {
        const int instance = r.i8();
        const int steps = r.i8() % 6;  // 3 or 5 are motion, 0 none, the others refused
        float xf[5 * 12];
        r.floats(xf, 5 * 12);
        check(lt_scene_set_instance_motion(scene, instance, xf, steps));
        break;
      }
      case lt_fuzz::kClearLights:
        check(lt_scene_clear_lights(scene));
        break;
      case lt_fuzz::kCommit:
        check(lt_scene_commit(scene));
        break;
      case lt_fuzz::kRender:
        render(scene, r);
        break;
    }
  }
  lt_scene_destroy(scene);
  return 0;
}
