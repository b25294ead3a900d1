// The C ABI: validates every input before it reaches the core, turns exceptions into status codes
// and lt_last_error() messages. No exception crosses this boundary.
#include "lantern/lantern.h"

#include <array>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <string>

#include "api/abi_layout.h"
#include "api/handles.h"
#include "core/cryptomatte.h"
#include "core/error.h"
#include "io/exr.h"
#include "io/image_file.h"
#include "io/vdb.h"
#include "media/grid_emission.h"
#include "media/volume_material.h"
#include "render/render.h"
#include "scene/lights/area.h"
#include "scene/lights/point.h"
#include "scene/lights/sun.h"
#include "scene/scene.h"
#include "shading/inputs.h"
#include "shading/shaders.h"
#include "shading/textures.h"

namespace {

using lt::InvalidArgument;

constexpr int kMaxLightgroups = 1024;  // lt_render_settings.lightgroup_count

template <class F>
int guarded(F f) {
  try {
    f();
    return LT_OK;
  } catch (const lt::InvalidArgument& e) {
    lt::set_last_error(e.what());
    return LT_ERROR_INVALID_ARGUMENT;
  } catch (const lt::StateError& e) {
    lt::set_last_error(e.what());
    return LT_ERROR_STATE;
  } catch (const lt::IoError& e) {
    lt::set_last_error(e.what());
    return LT_ERROR_IO;
  } catch (const lt::OutOfMemory& e) {
    lt::set_last_error(e.what());
    return LT_ERROR_OUT_OF_MEMORY;
  } catch (const std::bad_alloc&) {
    lt::set_last_error("out of memory");
    return LT_ERROR_OUT_OF_MEMORY;
  } catch (const std::exception& e) {
    lt::set_last_error(std::string("internal error: ") + e.what());
    return LT_ERROR_INTERNAL;
  } catch (...) {
    lt::set_last_error("internal error");
    return LT_ERROR_INTERNAL;
  }
}

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidArgument(message);
}

bool finite_array(const float* v, size_t n) {
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

lt::Transform to_transform(const float* m, const char* what) {
  require(finite_array(m, 12), std::string(what) + " transform is not finite");
  lt::Transform t;
  std::memcpy(t.m, m, sizeof(t.m));
  return t;
}

// Attribute `name` of mesh m (lt_mesh_attribute, lt_curves_attribute), checked: `elements`
// values of `components` floats each (one per `element`).
lt::MeshAttribute checked_attribute(const lt::Mesh& m, const std::string& name, int id, int components,
                                    const float* values, int value_count, size_t elements, const char* element) {
  require(id >= 0 && id < lt::kMaxAttributeId,
          name + ": id " + std::to_string(id) + " out of range [0, " + std::to_string(lt::kMaxAttributeId) + ")");
  require(m.attribute(id) == nullptr, name + ": id " + std::to_string(id) + " given twice");
  require(components >= 1 && components <= 4, name + ": components must be 1 to 4");
  const size_t n = elements * size_t(components);
  require(value_count >= 0 && size_t(value_count) == n, name + ": " + std::to_string(value_count) +
                                                            " values, expected " + std::to_string(n) + " (" +
                                                            std::to_string(components) + " per " + element + ")");
  require(n == 0 || values, name + ": values are NULL");
  require(finite_array(values, n), name + ": values must be finite");
  lt::MeshAttribute attr;
  attr.id = id;
  attr.components = components;
  attr.values.assign(values, values + n);
  return attr;
}

// Motion blur steps (lt_mesh_desc, lt_instance_desc, lt_camera_desc): 0, or an odd count from 3 to
// 129 (Cycles' 2^steps + 1 with steps 1 to 7; Embree's RTC_MAX_TIME_STEP_COUNT), so that the
// centre step is the shutter's centre.
void require_motion_steps(int count, const void* data, const std::string& what) {
  require(count == 0 || (count >= 3 && count <= 129 && count % 2 == 1),
          what + ": " + std::to_string(count) + " motion steps; expected 0 or an odd count from 3 to 129");
  require(count == 0 || data, what + ": motion steps are NULL");
}

// The steps of 12 floats each, copied as given (non-finite ones are caught where they are used).
std::vector<lt::Transform> motion_transforms(const float* m, int count) {
  std::vector<lt::Transform> steps(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) std::memcpy(steps[size_t(i)].m, m + 12 * i, sizeof(steps[size_t(i)].m));
  return steps;
}

lt::VolumeCoefficients to_volume(const lt_volume_desc* d) {
  require(d != nullptr, "volume description is NULL");
  require(d->node >= LT_VOLUME_PRINCIPLED && d->node <= LT_VOLUME_EMISSION,
          "unknown volume node " + std::to_string(d->node) + "; valid: PRINCIPLED, SCATTER, ABSORPTION, EMISSION");
  require(finite_array(d->color, 3) && finite_array(d->absorption_color, 3) && std::isfinite(d->density) &&
              std::isfinite(d->anisotropy),
          "volume colour, density, absorption colour and anisotropy must be finite");
  require(std::isfinite(d->emission_strength) && finite_array(d->emission_color, 3) &&
              std::isfinite(d->blackbody_intensity) && finite_array(d->blackbody_tint, 3) &&
              std::isfinite(d->temperature),
          "volume emission strength, colour, blackbody intensity, tint and temperature must be finite");
  lt::VolumeCoefficients c = lt::volume_coefficients(
      lt::VolumeNode(d->node), lt::Vec3(d->color[0], d->color[1], d->color[2]), d->density,
      lt::Vec3(d->absorption_color[0], d->absorption_color[1], d->absorption_color[2]), d->anisotropy);
  const lt::Vec3 emission_color(d->emission_color[0], d->emission_color[1], d->emission_color[2]);
  if (d->node == LT_VOLUME_PRINCIPLED)
    c.emission = lt::principled_volume_emission(
        d->emission_strength, emission_color, d->blackbody_intensity,
        lt::Vec3(d->blackbody_tint[0], d->blackbody_tint[1], d->blackbody_tint[2]), d->temperature);
  else if (d->node == LT_VOLUME_EMISSION)
    c.emission = lt::principled_volume_emission(d->emission_strength, emission_color, 0, lt::Vec3(0.0f), 0);
  return c;
}

bool named(const char* grid) { return grid && *grid; }

// The grid names of a component (lt_volume_desc's emission_strength_grid ... temperature_attribute).
std::array<const char*, 4> grid_names(const lt_volume_desc& d) {
  return {d.emission_strength_grid, d.blackbody_intensity_grid, d.temperature_grid, d.temperature_attribute};
}

// The sum of a volume's components (docs/volumes.md, "Volume shader mixes"). Grid names are read by
// Volume objects only (lt_scene_add_volume_grid), which evaluate the emission per lookup.
lt::VolumeMix to_volume_mix(const lt_volume_desc* d, int count, bool grids_allowed) {
  require(d != nullptr, "volume description is NULL");
  require(count >= 1 && count <= 64, "volume component count must be in [1, 64], got " + std::to_string(count));
  std::vector<lt::VolumeCoefficients> c;
  for (int i = 0; i < count; ++i) {
    c.push_back(to_volume(d + i));
    for (const char* g : grid_names(d[i]))
      require(grids_allowed || !named(g),
              "volume grids are read by Volume objects only (grid '" + std::string(named(g) ? g : "") + "')");
  }
  return lt::sum_volume_components(c.data(), count);
}

// A Volume object's emission: each emitting component with its parameters' grids (indices into
// *names, which collects the grids' names); empty if nothing emits.
std::vector<lt::EmissionComponent> grid_emission_components(const lt_volume_desc* d, int count,
                                                            std::vector<std::string>* names) {
  auto index = [&](const char* g) {
    if (!named(g)) return -1;
    for (size_t k = 0; k < names->size(); ++k)
      if ((*names)[k] == g) return int(k);
    names->push_back(g);
    return int(names->size()) - 1;
  };
  auto v3 = [](const float* f) { return lt::Vec3(f[0], f[1], f[2]); };
  std::vector<lt::EmissionComponent> out;
  for (int i = 0; i < count; ++i) {
    const lt_volume_desc& c = d[i];
    if (c.node != LT_VOLUME_PRINCIPLED && c.node != LT_VOLUME_EMISSION) continue;
    lt::EmissionComponent e;
    e.strength = {c.emission_strength, index(c.emission_strength_grid)};
    e.color = v3(c.emission_color);
    if (c.node == LT_VOLUME_PRINCIPLED) {
      e.blackbody = {c.blackbody_intensity, index(c.blackbody_intensity_grid)};
      e.temperature = {c.temperature, index(c.temperature_grid)};
      e.temperature_attribute = index(c.temperature_attribute);
      e.tint = v3(c.blackbody_tint);
    }
    if (e.strength.value > 0 || e.blackbody.value > 0) out.push_back(e);
  }
  return out;
}

lt::Medium homogeneous_medium(const lt::VolumeMix& v) {
  lt::Medium m = lt::Medium::homogeneous(v.sigma_a, v.sigma_s, v.phase.g[0]);
  m.set_phase(v.phase);
  m.set_emission(v.emission);
  return m;
}

// Edits that a committed scene also takes (viewport updates): refused while a render reads it.
// needs_commit: the edit changes what commit builds (the camera does not: renders read it at start).
void begin_edit(lt_scene* scene, bool needs_commit = true) {
  if (scene->live_renders.load() > 0)
    throw lt::StateError("the scene has a render that is not destroyed; destroy it before editing the scene");
  if (needs_commit) scene->scene.mark_edited();
}

lt::Material to_material(const lt_scene* scene, const lt_shader_program* p);

constexpr int kMaxDimension = 65536;

constexpr long long kMaxPixels = 1LL << 28;  // 268 M pixels: beyond this a render is a mistake

bool known_interpolation(int i) { return i == LT_INTERP_LINEAR || i == LT_INTERP_CLOSEST || i == LT_INTERP_CUBIC; }

void check_image(const lt_image_desc& d) {
  require(d.width > 0 && d.height > 0 && d.width <= kMaxDimension && d.height <= kMaxDimension,
          "image size " + std::to_string(d.width) + "x" + std::to_string(d.height) + " is out of range");
  require(d.channels == 1 || d.channels == 3 || d.channels == 4,
          "image has " + std::to_string(d.channels) + " channels; 1, 3 or 4 are supported");
  require(known_interpolation(d.interpolation), "unknown image interpolation");
  require(d.extension >= LT_EXTENSION_REPEAT && d.extension <= LT_EXTENSION_CLIP, "unknown image extension");
  require(
      d.alpha >= LT_ALPHA_IGNORE && d.alpha <= LT_ALPHA_CHANNEL_PACKED,
      "unknown image alpha " + std::to_string(d.alpha) + "; valid: IGNORE, STRAIGHT, PREMULTIPLIED, CHANNEL_PACKED");
  if (d.ocio_space && *d.ocio_space) {
    require(d.ocio_config && *d.ocio_config,
            "colour space '" + std::string(d.ocio_space) + "' without a configuration");
    require(d.srgb == 0, "an image in colour space '" + std::string(d.ocio_space) + "' is not also sRGB-encoded");
  }
}

// lt_interpolation, for images given by the caller and read from files alike (one filter each,
// shading/image.cpp, whatever the storage).
lt::Interpolation interpolation(int i) {
  return i == LT_INTERP_CLOSEST ? lt::Interpolation::Closest
         : i == LT_INTERP_CUBIC ? lt::Interpolation::Cubic
                                : lt::Interpolation::Linear;
}

// An image the caller gives (lt_image_desc), converted from another colour space when it names one.
std::unique_ptr<lt::Image> given_image(const lt_image_desc& d, lt::FloatBuffer pixels, const std::string& ocio_config,
                                       const std::string& ocio_space) {
  if (!ocio_space.empty())
    return lt::byte_image_to_scene_linear(d.width, d.height, d.channels, std::move(pixels), lt::ImageAlpha(d.alpha),
                                          interpolation(d.interpolation), lt::Extension(d.extension), ocio_config,
                                          ocio_space);
  return std::make_unique<lt::Image>(d.width, d.height, d.channels, std::move(pixels), d.srgb != 0,
                                     interpolation(d.interpolation), lt::Extension(d.extension),
                                     lt::ImageAlpha(d.alpha));
}
std::string text_or_empty(const char* s) { return s ? s : ""; }

lt::Program to_program(const lt_scene* scene, const lt_shader_program* p) {
  require(p->code_words >= 0 && p->code_words <= lt::kMaxProgramWords,
          "shader program length " + std::to_string(p->code_words) + " is out of range");
  require(p->constant_count >= 0 && p->constant_count <= lt::kMaxProgramWords,
          "shader program constant count " + std::to_string(p->constant_count) + " is out of range");
  require(p->code_words == 0 || p->code, "shader program code is NULL");
  require(p->constant_count == 0 || p->constants, "shader program constants are NULL");
  return lt::Program(std::vector<uint32_t>(p->code, p->code + p->code_words),
                     std::vector<float>(p->constants, p->constants + p->constant_count), p->registers,
                     scene->scene.images.size());
}

lt::Material to_material(const lt_scene* scene, const lt_shader_program* p) {
  return lt::Material(to_program(scene, p));
}

// lt_world_desc's image as a world program: Emission(weight scale, colour Environment Texture of
// the direction rotated about Z by rotation (the Texture Coordinate's Object output with that
// matrix), strength 1).
lt::Program image_world_program(const lt_scene* scene, int image, float rotation, const lt::Vec3& scale) {
  const float c = std::cos(rotation), s = std::sin(rotation);
  std::vector<float> k = {12,      c,       -s,      0, 0, s, c, 0, 0, 0, 0, 1, 0,  // object table (rows)
                          0,                                                        // camera table: none
                          scale.x, scale.y, scale.z, 1};
  const uint32_t v3 = 3u << 24, f1 = 1u << 24;
  std::vector<uint32_t> code = {lt::kOpTexCoord, 7u << 8 | 3u << 16};
  for (uint32_t r = 0; r < 7; ++r) code.push_back(v3 | 3 * r);
  code.insert(code.end(), {0u, 13u, 0u});
  code.insert(code.end(),
              {lt::kOpEnvironment, 1u | 2u << 8 | 3u << 16, v3 | 9u, v3 | 21u, f1 | 24u, uint32_t(image), 0u, 0u});
  code.insert(code.end(), {lt::kOpEmission, 3u, lt::kConstBit | v3 | 14u, v3 | 21u, lt::kConstBit | f1 | 17u});
  return lt::Program(std::move(code), std::move(k), 25, scene->scene.images.size());
}

// Object Info's colour and pass index and the object attributes, checked before any is set.
void set_object_values(lt::Instance* inst, const float color[4], int pass_index, const int* ids, const float* values,
                       int count) {
  require(finite_array(color, 4), "instance colour must be finite");
  require(count >= 0 && (count == 0 || (ids && values)), "instance attributes are NULL or their count negative");
  require(finite_array(values, 4 * size_t(count)), "instance attribute values must be finite");
  std::vector<lt::InstanceAttribute> attributes(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    lt::InstanceAttribute& a = attributes[size_t(i)];
    a.id = ids[i];
    require(a.id >= 0 && a.id < lt::kMaxAttributeId, "instance attribute id " + std::to_string(a.id) + " out of range");
    std::copy(values + 4 * i, values + 4 * i + 4, a.value);
  }
  std::copy(color, color + 4, inst->color);
  inst->pass_index = float(pass_index);
  inst->attributes = std::move(attributes);
}

}  // namespace

extern "C" {

int lt_abi_version(void) { return LT_ABI_VERSION; }
const char* lt_version(void) { return "0.1.0"; }
const char* lt_last_error(void) { return lt::last_error(); }

int lt_scene_create(lt_scene** out) {
  return guarded([&] {
    require(out != nullptr, "lt_scene_create: out is NULL");
    *out = new lt_scene();
  });
}

void lt_scene_destroy(lt_scene* scene) { delete scene; }

int lt_scene_warning_count(const lt_scene* scene) { return scene ? int(scene->scene.warnings.size()) : 0; }

const char* lt_scene_warning(const lt_scene* scene, int index) {
  if (!scene || index < 0 || index >= int(scene->scene.warnings.size())) return "";
  return scene->scene.warnings[index].c_str();
}

int lt_scene_add_image(lt_scene* scene, const lt_image_desc* d, int* out_id) {
  return guarded([&] {
    require(scene && d && out_id, "lt_scene_add_image: NULL argument");
    scene->scene.require_editable();
    check_image(*d);
    require(d->pixels != nullptr, "image pixels are NULL");
    auto& images = scene->scene.images;
    lt::FloatBuffer px(size_t(d->width) * d->height * d->channels);  // the one copy Image would make
    std::memcpy(px.data(), d->pixels, px.size() * sizeof(float));
    images.push_back(given_image(*d, std::move(px), text_or_empty(d->ocio_config), text_or_empty(d->ocio_space)));
    *out_id = int(images.size()) - 1;
  });
}

int lt_scene_begin_image(lt_scene* scene, const lt_image_desc* d, float** out_pixels) {
  return guarded([&] {
    require(scene && d && out_pixels, "lt_scene_begin_image: NULL argument");
    scene->scene.require_editable();
    check_image(*d);
    *out_pixels = nullptr;
    scene->pending_image.reset();  // an unfinished image is dropped
    auto p = std::make_unique<lt_scene::PendingImage>();
    p->desc = *d;
    p->desc.pixels = nullptr;
    p->ocio_config = text_or_empty(d->ocio_config);
    p->ocio_space = text_or_empty(d->ocio_space);
    p->desc.ocio_config = p->desc.ocio_space = nullptr;
    p->pixels = lt::FloatBuffer(size_t(d->width) * d->height * d->channels);
    *out_pixels = p->pixels.data();
    scene->pending_image = std::move(p);
  });
}

int lt_scene_end_image(lt_scene* scene, int* out_id) {
  return guarded([&] {
    require(scene && out_id, "lt_scene_end_image: NULL argument");
    scene->scene.require_editable();
    if (!scene->pending_image) throw lt::StateError("lt_scene_end_image: no image was begun");
    std::unique_ptr<lt_scene::PendingImage> p = std::move(scene->pending_image);
    const lt_image_desc& d = p->desc;
    auto& images = scene->scene.images;
    images.push_back(given_image(d, std::move(p->pixels), p->ocio_config, p->ocio_space));
    *out_id = int(images.size()) - 1;
  });
}

int lt_scene_add_image_file(lt_scene* scene, const lt_image_file_desc* d, int* out_id) {
  return guarded([&] {
    require(scene && d && out_id, "lt_scene_add_image_file: NULL argument");
    scene->scene.require_editable();
    require(d->path != nullptr && *d->path != '\0', "image file path is empty");
    require(d->color_space >= LT_COLOR_SPACE_SRGB && d->color_space <= LT_COLOR_SPACE_OTHER,
            "unknown colour space " + std::to_string(d->color_space));
    require(d->alpha_mode >= LT_ALPHA_MODE_STRAIGHT && d->alpha_mode <= LT_ALPHA_MODE_NONE,
            "unknown alpha mode " + std::to_string(d->alpha_mode));
    require(known_interpolation(d->interpolation), "unknown image interpolation");
    require(d->extension >= LT_EXTENSION_REPEAT && d->extension <= LT_EXTENSION_CLIP, "unknown image extension");
    lt::ImageFileRequest r;
    r.path = d->path;
    r.space = lt::FileColorSpace(d->color_space);
    r.alpha_mode = lt::FileAlphaMode(d->alpha_mode);
    r.use_alpha = d->use_alpha != 0;
    r.interp = interpolation(d->interpolation);
    r.ext = lt::Extension(d->extension);
    if (d->color_space == LT_COLOR_SPACE_OTHER && d->ocio_space && *d->ocio_space) {
      require(d->ocio_config && *d->ocio_config,
              "colour space '" + std::string(d->ocio_space) + "' without a configuration");
      r.ocio_config = d->ocio_config;
      r.ocio_space = d->ocio_space;
    }
    std::unique_ptr<lt::Image> image;
    try {
      image = lt::read_image_file(r);
    } catch (const lt::ImageFileUnsupported& e) {
      throw InvalidArgument(e.what());
    }
    auto& images = scene->scene.images;
    images.push_back(std::move(image));
    *out_id = int(images.size()) - 1;
  });
}

int lt_scene_add_material(lt_scene* scene, const lt_shader_program* program, int* out_id) {
  return guarded([&] {
    require(scene && program && out_id, "lt_scene_add_material: NULL argument");
    scene->scene.require_editable();
    scene->scene.materials.push_back(to_material(scene, program));
    *out_id = int(scene->scene.materials.size()) - 1;
  });
}

int lt_scene_set_material_pass_index(lt_scene* scene, int material, int pass_index) {
  return guarded([&] {
    require(scene, "lt_scene_set_material_pass_index: NULL argument");
    require(material >= 0 && material < int(scene->scene.materials.size()),
            "material " + std::to_string(material) + " does not exist");
    scene->scene.materials[material].set_pass_index(float(pass_index));
  });
}

uint32_t lt_cryptomatte_hash(const char* bytes, size_t length) { return bytes ? lt::murmur3_32(bytes, length, 0) : 0u; }

int lt_scene_set_material_cryptomatte(lt_scene* scene, int material, uint32_t hash) {
  return guarded([&] {
    require(scene, "lt_scene_set_material_cryptomatte: NULL argument");
    require(material >= 0 && material < int(scene->scene.materials.size()),
            "material " + std::to_string(material) + " does not exist");
    scene->scene.materials[material].set_crypto_id(hash ? lt::cryptomatte_id(hash) : 0.0f);
  });
}

int lt_scene_set_material(lt_scene* scene, int material, const lt_shader_program* program) {
  return guarded([&] {
    require(scene && program, "lt_scene_set_material: NULL argument");
    require(material >= 0 && material < int(scene->scene.materials.size()),
            "material " + std::to_string(material) + " does not exist");
    lt::Material m = to_material(scene, program);  // validated before anything changes
    m.set_pass_index(scene->scene.materials[material].pass_index());
    m.set_crypto_id(scene->scene.materials[material].crypto_id());
    m.keep_displacement_of(scene->scene.materials[material]);
    begin_edit(scene);
    scene->scene.materials[material] = std::move(m);
  });
}

int lt_scene_set_material_displacement(lt_scene* scene, int material, const lt_shader_program* program, int method) {
  return guarded([&] {
    require(scene, "lt_scene_set_material_displacement: NULL argument");
    scene->scene.require_editable();  // meshes are displaced once, at the first commit
    require(material >= 0 && material < int(scene->scene.materials.size()),
            "material " + std::to_string(material) + " does not exist");
    require(method >= LT_DISPLACEMENT_BUMP && method <= LT_DISPLACEMENT_BOTH,
            "unknown displacement method " + std::to_string(method));
    require((method == LT_DISPLACEMENT_BUMP) == (program == nullptr),
            "a displacement program goes with the methods TRUE and BOTH, and only with them");
    std::shared_ptr<const lt::Program> p;
    if (program) p = std::make_shared<const lt::Program>(to_program(scene, program));
    scene->scene.materials[material].set_displacement(
        std::move(p), method == LT_DISPLACEMENT_TRUE ? lt::DisplacementMethod::True : lt::DisplacementMethod::Both);
  });
}

int lt_scene_add_mesh(lt_scene* scene, const lt_mesh_desc* d, int* out_id) {
  return guarded([&] {
    require(scene && d && out_id, "lt_scene_add_mesh: NULL argument");
    scene->scene.require_editable();
    require(d->vertex_count >= 0 && d->triangle_count >= 0, "mesh counts must not be negative");
    require(d->vertex_count <= (1 << 28) && d->triangle_count <= (1 << 28), "mesh is too large");
    require(d->vertex_count == 0 || d->positions, "mesh positions are NULL");
    require(d->triangle_count == 0 || d->triangles, "mesh triangles are NULL");
    lt::Mesh m;
    m.positions.resize(d->vertex_count);
    for (int i = 0; i < d->vertex_count; ++i)
      m.positions[i] = lt::Vec3(d->positions[3 * i], d->positions[3 * i + 1], d->positions[3 * i + 2]);
    const size_t corners = size_t(d->triangle_count) * 3;
    m.indices.resize(corners);
    for (size_t c = 0; c < corners; ++c) {
      int idx = d->triangles[c];
      if (idx < 0 || idx >= d->vertex_count)
        throw InvalidArgument("mesh triangle " + std::to_string(c / 3) + " has vertex index " + std::to_string(idx) +
                              " out of range [0, " + std::to_string(d->vertex_count) + ")");
      m.indices[c] = uint32_t(idx);
    }
    if (d->corner_normals && corners) {
      m.corner_normals.resize(corners);
      for (size_t c = 0; c < corners; ++c)
        m.corner_normals[c] =
            lt::Vec3(d->corner_normals[3 * c], d->corner_normals[3 * c + 1], d->corner_normals[3 * c + 2]);
    }
    if (d->flat_triangles && !m.corner_normals.empty()) {
      m.flat.assign(d->flat_triangles, d->flat_triangles + d->triangle_count);
      for (uint8_t& f : m.flat) f = f != 0;
    }
    if (d->corner_uvs && corners) {
      m.corner_uvs.resize(corners);
      for (size_t c = 0; c < corners; ++c) {
        float u = d->corner_uvs[2 * c], v = d->corner_uvs[2 * c + 1];
        m.corner_uvs[c] = {std::isfinite(u) ? u : 0.0f, std::isfinite(v) ? v : 0.0f};
      }
    }
    if (d->material_slots && d->triangle_count) {
      m.slots.assign(d->material_slots, d->material_slots + d->triangle_count);
      for (int& s : m.slots) s = s < 0 ? 0 : s;  // Blender's indices are never negative; be safe
    }
    require(d->attribute_count >= 0 && (d->attribute_count == 0 || d->attributes),
            "mesh attributes are NULL or their count negative");
    for (int i = 0; i < d->attribute_count; ++i) {
      const lt_mesh_attribute& a = d->attributes[i];
      m.attributes.push_back(checked_attribute(m, "mesh attribute " + std::to_string(i), a.id, a.components, a.values,
                                               a.value_count, corners, "corner"));
    }
    require_motion_steps(d->motion_step_count, d->motion_positions, "mesh");
    if (d->motion_step_count > 0) {
      const size_t n = 3 * size_t(d->vertex_count) * size_t(d->motion_step_count);
      require(finite_array(d->motion_positions, n), "mesh motion positions must be finite");
      m.motion_steps = d->motion_step_count;
      m.motion_positions.resize(n / 3);
      for (size_t i = 0; i < n / 3; ++i)
        m.motion_positions[i] =
            lt::Vec3(d->motion_positions[3 * i], d->motion_positions[3 * i + 1], d->motion_positions[3 * i + 2]);
      if (d->motion_corner_normals && !m.corner_normals.empty()) {
        const size_t nc = corners * size_t(d->motion_step_count);
        m.motion_corner_normals.resize(nc);
        for (size_t c = 0; c < nc; ++c)
          m.motion_corner_normals[c] = lt::Vec3(d->motion_corner_normals[3 * c], d->motion_corner_normals[3 * c + 1],
                                                d->motion_corner_normals[3 * c + 2]);
      }
    }
    const lt::Vec3 loc(d->texspace_location[0], d->texspace_location[1], d->texspace_location[2]);
    const lt::Vec3 size(d->texspace_size[0], d->texspace_size[1], d->texspace_size[2]);
    if (lt::is_finite(loc) && lt::is_finite(size) && size.x > 0 && size.y > 0 && size.z > 0) {
      m.texspace_location = loc;
      m.texspace_size = size;
    } else {
      // Blender's automatic texture space (BKE_mesh_texspace_calc): the bounds, flat axes of size 1.
      lt::Bounds b;
      for (const lt::Vec3& v : m.positions) b.extend(v);
      if (!b.empty()) {
        m.texspace_location = (b.lo + b.hi) * 0.5f;
        m.texspace_size = (b.hi - b.lo) * 0.5f;
        for (int k = 0; k < 3; ++k) {
          float& s = m.texspace_size[k];
          s = s == 0 ? 1.0f : std::max(s, 1e-5f);
        }
      }
    }
    *out_id = scene->scene.geometry.add_mesh(std::move(m), scene->scene.warnings);
  });
}

int lt_scene_add_curves(lt_scene* scene, const lt_curves_desc* d, int* out_id) {
  return guarded([&] {
    require(scene && d && out_id, "lt_scene_add_curves: NULL argument");
    scene->scene.require_editable();
    require(d->point_count <= (1u << 30) && d->curve_count < (1u << 30), "curves are too large");
    require(d->point_count == 0 || d->points, "curve points are NULL");
    require(d->curve_count == 0 || d->curve_offsets, "curve offsets are NULL");
    lt::Mesh m;
    m.kind = d->curve_count ? lt::GeometryKind::Curves : lt::GeometryKind::Points;
    m.curves.cps.assign(d->points, d->points + size_t(d->point_count) * 4);
    std::vector<uint32_t> offsets;
    if (d->curve_count) {
      offsets.assign(d->curve_offsets, d->curve_offsets + d->curve_count + 1);
      require(offsets.front() == 0 && offsets.back() == d->point_count,
              "curve offsets must start at 0 and end at the point count");
      for (size_t k = 0; k + 1 < offsets.size(); ++k)
        require(offsets[k] <= offsets[k + 1], "curve offsets must not decrease (curve " + std::to_string(k) + ")");
      if (d->material_slots) {
        m.slots.assign(d->material_slots, d->material_slots + d->curve_count);
        for (int& s : m.slots) s = s < 0 ? 0 : s;
      }
    }
    require(d->attribute_count >= 0 && (d->attribute_count == 0 || d->attributes),
            "curve attributes are NULL or their count negative");
    for (int i = 0; i < d->attribute_count; ++i) {
      const lt_curves_attribute& a = d->attributes[i];
      const bool per_point = a.per_point || !d->curve_count;
      m.attributes.push_back(checked_attribute(m, "curve attribute " + std::to_string(i), a.id, a.components, a.values,
                                               a.value_count, per_point ? d->point_count : d->curve_count,
                                               per_point ? "point" : "curve"));
      m.attributes.back().per_point = per_point;
    }
    if (d->curve_uvs && d->curve_count) {
      require(finite_array(d->curve_uvs, 2 * size_t(d->curve_count)), "curve UVs must be finite");
      m.curves.uv.resize(d->curve_count);
      for (size_t k = 0; k < d->curve_count; ++k)
        m.curves.uv[k] = lt::Vec2{d->curve_uvs[2 * k], d->curve_uvs[2 * k + 1]};
    }
    if (d->generated_from_root && d->curve_count) {
      require(finite_array(d->texspace_location, 3) && finite_array(d->texspace_size, 3),
              "curve texture space must be finite");
      m.curves.generated_from_root = true;
      m.texspace_location = lt::Vec3(d->texspace_location[0], d->texspace_location[1], d->texspace_location[2]);
      m.texspace_size = lt::Vec3(d->texspace_size[0], d->texspace_size[1], d->texspace_size[2]);
    }
    require_motion_steps(d->motion_step_count, d->motion_points, "curves");
    if (d->motion_step_count > 0) {
      m.curves.motion_steps = d->motion_step_count;
      m.curves.motion_cps.assign(d->motion_points,
                                 d->motion_points + size_t(d->point_count) * 4 * size_t(d->motion_step_count));
    }
    // Cycles' Random of a curve or point: hash_uint2_to_float(index, 0).
    const size_t n = d->curve_count ? d->curve_count : d->point_count;
    m.curves.random.resize(n);
    for (size_t k = 0; k < n; ++k) m.curves.random[k] = float(lt::tex::hash_uint2(uint32_t(k), 0)) / float(0xFFFFFFFFu);
    *out_id = scene->scene.geometry.add_curves(std::move(m), offsets, scene->scene.warnings);
  });
}

int lt_scene_add_instance(lt_scene* scene, const lt_instance_desc* d, int* out_id) {
  return guarded([&] {
    require(scene && d && out_id, "lt_scene_add_instance: NULL argument");
    scene->scene.require_editable();
    require(d->mesh >= 0 && d->mesh < int(scene->scene.geometry.mesh_count()),
            "instance refers to mesh " + std::to_string(d->mesh) + ", which does not exist");
    require(d->material_count >= 0 && (d->material_count == 0 || d->materials), "instance materials are NULL");
    lt::Instance inst;
    inst.mesh = d->mesh;
    bool finite = finite_array(d->transform, 12);
    if (finite)
      std::memcpy(inst.xf.m, d->transform, sizeof(inst.xf.m));
    else
      std::memset(inst.xf.m, 0, sizeof(inst.xf.m));  // scaled to a point: nothing is hit
    for (int i = 0; i < d->material_count; ++i) {
      int m = d->materials[i];
      require(m >= -1 && m < int(scene->scene.materials.size()),
              "instance material " + std::to_string(m) + " does not exist");
      inst.materials.push_back(m);
    }
    inst.visibility = d->visibility & LT_VISIBLE_ALL;
    inst.holdout = d->holdout != 0;
    inst.shadow_catcher = d->shadow_catcher != 0;
    auto unit = [](float x) { return x >= 0 && x <= 1; };
    require(unit(d->shadow_terminator_geometry_offset) && unit(d->shadow_terminator_shading_offset),
            "instance shadow terminator offsets must lie in [0, 1]");
    inst.terminator_geometry = d->shadow_terminator_geometry_offset;
    // Cycles' scene/object.cpp turns the shading offset into the cosine's frequency multiplier.
    inst.terminator_frequency = 1 / (1 - 0.5f * d->shadow_terminator_shading_offset);
    require(d->lightgroup >= 0 && d->lightgroup <= kMaxLightgroups, "instance light group out of range");
    inst.lightgroup = d->lightgroup - 1;
    set_object_values(&inst, d->color, d->pass_index, d->attribute_ids, d->attribute_values, d->attribute_count);
    // Cycles' object random number (scene/object.cpp): the id over 0xFFFFFFFF, in floats.
    inst.random = float(d->random_id) * (1.0f / float(0xFFFFFFFFu));
    inst.crypto_object = d->cryptomatte_object ? lt::cryptomatte_id(d->cryptomatte_object) : 0.0f;
    inst.crypto_asset = d->cryptomatte_asset ? lt::cryptomatte_id(d->cryptomatte_asset) : 0.0f;
    require_motion_steps(d->motion_step_count, d->motion_transforms, "instance");
    if (finite) inst.motion = motion_transforms(d->motion_transforms, d->motion_step_count);
    *out_id = scene->scene.geometry.add_instance(std::move(inst), scene->scene.warnings);
    if (!finite)
      scene->scene.warnings.push_back("instance " + std::to_string(*out_id) + " has a non-finite transform; left out");
  });
}

int lt_scene_add_light(lt_scene* scene, const lt_light_desc* d) {
  return guarded([&] {
    require(scene && d, "lt_scene_add_light: NULL argument");
    begin_edit(scene);
    require(d->type >= LT_LIGHT_POINT && d->type <= LT_LIGHT_SUN,
            "unknown light type " + std::to_string(d->type) + "; valid types are POINT, SPOT, AREA, SUN");
    // Negative energy is negative light, as Cycles renders it.
    require(finite_array(d->color, 3), "light colour x energy must be finite");
    lt::Transform xf = to_transform(d->transform, "light");
    const lt::Spectrum power(d->color[0], d->color[1], d->color[2]);
    auto& warnings = scene->scene.warnings;
    const std::string name = "light " + std::to_string(scene->scene.lamp_lights.size());
    if (lt::is_black(power)) {
      warnings.push_back(name + " emits nothing; left out");
      return;
    }
    // Blender's numbers become lights (and radiance) in scene/lights/: point.h, area.h, sun.h.
    lt::Light l;
    switch (d->type) {
      case LT_LIGHT_POINT:
      case LT_LIGHT_SPOT:
        require(std::isfinite(d->radius) && d->radius >= 0, name + ": radius must be finite and >= 0");
        if (d->type == LT_LIGHT_POINT) {
          l = lt::point_lamp(power, xf, d->radius);
        } else {
          require(std::isfinite(d->spot_size) && std::isfinite(d->spot_blend), name + ": spot size/blend not finite");
          l = lt::spot_lamp(power, xf, d->radius, d->spot_size, d->spot_blend);
          require(lt::is_finite(l.direction), name + ": the spot's transform has no direction");
        }
        break;
      case LT_LIGHT_AREA: {
        require(d->shape >= LT_AREA_SQUARE && d->shape <= LT_AREA_ELLIPSE, name + ": unknown area shape");
        require(std::isfinite(d->size_x) && std::isfinite(d->size_y), name + ": size not finite");
        const bool square = d->shape == LT_AREA_SQUARE || d->shape == LT_AREA_DISK;
        const bool round = d->shape == LT_AREA_DISK || d->shape == LT_AREA_ELLIPSE;
        l = lt::area_lamp(power, xf, round ? lt::AreaShape::Ellipse : lt::AreaShape::Rectangle, d->size_x,
                          square ? d->size_x : d->size_y);
        if (!(l.area > 1e-12f) || !std::isfinite(l.area) || !lt::is_finite(l.direction)) {
          warnings.push_back(name + ": area light of zero area; left out");
          return;
        }
        require(std::isfinite(d->spread), name + ": spread not finite");
        lt::set_area_spread(&l, d->spread);
        break;
      }
      case LT_LIGHT_SUN:
        require(std::isfinite(d->angle) && d->angle >= 0, name + ": sun angle must be finite and >= 0");
        l = lt::sun_lamp(power, xf, d->angle);
        require(lt::is_finite(l.direction), name + ": the sun's transform has no direction");
        break;
    }
    l.visibility = d->visibility & LT_VISIBLE_ALL;
    require(d->lightgroup >= 0 && d->lightgroup <= kMaxLightgroups, name + ": light group out of range");
    l.lightgroup = d->lightgroup - 1;
    scene->scene.lamp_lights.push_back(l);
  });
}

int lt_scene_clear_lights(lt_scene* scene) {
  return guarded([&] {
    require(scene != nullptr, "lt_scene_clear_lights: NULL scene");
    begin_edit(scene);
    scene->scene.lamp_lights.clear();
  });
}

int lt_scene_set_instance_transform(lt_scene* scene, int instance, const float transform[12]) {
  return guarded([&] {
    require(scene && transform, "lt_scene_set_instance_transform: NULL argument");
    require(instance >= 0 && instance < int(scene->scene.geometry.instance_count()),
            "instance " + std::to_string(instance) + " does not exist");
    lt::Transform xf = to_transform(transform, "instance");
    begin_edit(scene);
    scene->scene.geometry.set_instance_transform(instance, xf);
  });
}

int lt_scene_set_instance_motion(lt_scene* scene, int instance, const float* transforms, int steps) {
  return guarded([&] {
    require(scene, "lt_scene_set_instance_motion: NULL scene");
    require(instance >= 0 && instance < int(scene->scene.geometry.instance_count()),
            "instance " + std::to_string(instance) + " does not exist");
    require_motion_steps(steps, transforms, "instance");
    begin_edit(scene);
    scene->scene.geometry.set_instance_motion(instance, motion_transforms(transforms, steps), scene->scene.warnings);
  });
}

int lt_scene_set_instance_values(lt_scene* scene, int instance, unsigned visibility, const float color[4],
                                 int pass_index, const int* attribute_ids, const float* attribute_values,
                                 int attribute_count) {
  return guarded([&] {
    require(scene && color, "lt_scene_set_instance_values: NULL argument");
    require(instance >= 0 && instance < int(scene->scene.geometry.instance_count()),
            "instance " + std::to_string(instance) + " does not exist");
    lt::Instance values;
    values.visibility = visibility & LT_VISIBLE_ALL;
    set_object_values(&values, color, pass_index, attribute_ids, attribute_values, attribute_count);
    // The other values are read only while shading: nothing to rebuild for them.
    begin_edit(scene, values.visibility != scene->scene.geometry.instance(instance).visibility);
    scene->scene.geometry.set_instance_values(instance, std::move(values));
  });
}

int lt_scene_get_stats(const lt_scene* scene, lt_scene_stats* out) {
  return guarded([&] {
    require(scene && out, "lt_scene_get_stats: NULL argument");
    out->mesh_bvh_builds = scene->scene.geometry.mesh_builds();
    out->top_bvh_builds = scene->scene.geometry.top_builds();
    out->light_sampler_builds = scene->scene.light_builds();
    out->emissive_triangles = scene->scene.emissive_triangles();
    out->emissive_instances = scene->scene.emissive_instances();
    out->image_bytes = out->image_texels = out->byte_images = 0;
    for (const auto& im : scene->scene.images) {
      out->image_bytes += im->bytes();
      out->image_texels += uint64_t(im->width()) * im->height();
      out->byte_images += im->is_byte() ? 1 : 0;
    }
    out->world_map_width = uint64_t(scene->scene.world.map_width());
    out->world_map_height = uint64_t(scene->scene.world.map_height());
    out->motion_instances = scene->scene.geometry.motion_instances();
    out->motion_meshes = scene->scene.geometry.motion_meshes();
    out->camera_motion_steps = scene->scene.camera.motion.size();
    out->moving_volumes = 0;
    for (const lt::Medium& m : scene->scene.media) out->moving_volumes += m.moves() ? 1 : 0;
  });
}

int lt_scene_set_camera(lt_scene* scene, const lt_camera_desc* d) {
  return guarded([&] {
    require(scene && d, "lt_scene_set_camera: NULL argument");
    require(d->type == LT_CAMERA_PERSPECTIVE || d->type == LT_CAMERA_ORTHOGRAPHIC || d->type == LT_CAMERA_PANORAMA,
            "unknown camera type " + std::to_string(d->type) + "; valid types are PERSPECTIVE, ORTHOGRAPHIC, PANORAMA");
    require(d->sensor_fit >= LT_SENSOR_AUTO && d->sensor_fit <= LT_SENSOR_VERTICAL, "unknown sensor fit");
    const float values[] = {d->focal_length, d->sensor_width, d->sensor_height, d->ortho_scale, d->shift_x,
                            d->shift_y,      d->clip_start,   d->clip_end,      d->pixel_aspect};
    require(finite_array(values, 9), "camera parameters must be finite");
    require(
        d->focal_length > 0 && d->sensor_width > 0 && d->sensor_height > 0 && d->ortho_scale > 0 && d->pixel_aspect > 0,
        "camera focal length, sensor size, ortho scale and pixel aspect must be positive");
    require(d->clip_start >= 0 && d->clip_end > d->clip_start, "camera clip end must exceed clip start >= 0");
    const float lens_values[] = {d->focus_distance, d->aperture_fstop, d->aperture_rotation, d->aperture_ratio,
                                 d->fisheye_fov,    d->fisheye_lens,   d->latitude_min,      d->latitude_max,
                                 d->longitude_min,  d->longitude_max};
    require(finite_array(lens_values, 10) && finite_array(d->fisheye_polynomial, 5) &&
                finite_array(d->panorama_viewplane, 4) && std::isfinite(d->panorama_frame_aspect),
            "camera depth of field and panorama parameters must be finite");
    if (d->use_dof) {
      require(d->focus_distance > 0,
              "camera focus distance must be positive with depth of field (the plane in focus cannot be at the lens)");
      require(d->aperture_fstop >= 0, "camera F-stop must be >= 0");
      require(d->aperture_blades >= 0 && d->aperture_blades <= 16, "camera aperture blades must be in [0, 16]");
      require(d->aperture_ratio > 0, "camera aperture ratio must be positive");
    }
    if (d->type == LT_CAMERA_PANORAMA) {
      require(
          d->panorama_type >= LT_PANORAMA_EQUIRECTANGULAR && d->panorama_type <= LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE,
          "unknown panorama type " + std::to_string(d->panorama_type) +
              "; valid types are EQUIRECTANGULAR, FISHEYE_EQUIDISTANT, FISHEYE_EQUISOLID, MIRRORBALL, "
              "FISHEYE_LENS_POLYNOMIAL, EQUIANGULAR_CUBEMAP_FACE");
      require(d->fisheye_fov > 0 && d->fisheye_lens > 0, "camera fisheye field of view and lens must be positive");
    }
    lt::CameraDesc c = scene->scene.camera;  // assigned only once valid: a refused call changes nothing
    c.orthographic = d->type == LT_CAMERA_ORTHOGRAPHIC;
    c.panorama = d->type == LT_CAMERA_PANORAMA;
    c.aperture_radius =
        d->use_dof ? lt::aperture_radius_from_fstop(c.orthographic, d->focal_length, d->aperture_fstop) : 0.0f;
    c.focus_distance = d->focus_distance;
    c.aperture_blades = d->aperture_blades;
    c.aperture_rotation = d->aperture_rotation;
    c.aperture_ratio = d->aperture_ratio;
    c.panorama_type = lt::PanoramaType(d->panorama_type);
    c.fisheye_fov = d->fisheye_fov;
    c.fisheye_lens = d->fisheye_lens;
    c.latitude_min = d->latitude_min;
    c.latitude_max = d->latitude_max;
    c.longitude_min = d->longitude_min;
    c.longitude_max = d->longitude_max;
    std::copy(d->fisheye_polynomial, d->fisheye_polynomial + 5, c.polynomial);
    std::copy(d->panorama_viewplane, d->panorama_viewplane + 4, c.panorama_viewplane);
    c.panorama_frame_aspect = std::max(0.0f, d->panorama_frame_aspect);
    c.xf = to_transform(d->transform, "camera");
    require(std::abs(c.xf.determinant()) > 1e-30f, "camera transform is singular");
    c.focal_length = d->focal_length;
    c.sensor_width = d->sensor_width;
    c.sensor_height = d->sensor_height;
    c.sensor_fit = d->sensor_fit;
    c.ortho_scale = d->ortho_scale;
    c.shift_x = d->shift_x;
    c.shift_y = d->shift_y;
    c.clip_start = d->clip_start;
    c.clip_end = d->clip_end;
    c.pixel_aspect = d->pixel_aspect;
    for (float z : {d->zoom_pre, d->zoom_post})
      require(std::isfinite(z) && z >= 0, "camera zoom_pre and zoom_post must be finite and >= 0 (0: none)");
    c.zoom_pre = d->zoom_pre > 0 ? d->zoom_pre : 1.0f;
    c.zoom_post = d->zoom_post > 0 ? d->zoom_post : 1.0f;
    require_motion_steps(d->motion_step_count, d->motion_transforms, "camera");
    c.motion = motion_transforms(d->motion_transforms, d->motion_step_count);
    for (const lt::Transform& m : c.motion)
      if (!finite_array(m.m, 12) || !(std::abs(m.determinant()) > 1e-30f)) {
        scene->scene.warnings.push_back(
            "a camera motion step's transform is not finite or is singular: the camera renders without motion "
            "blur");
        c.motion.clear();
        break;
      }
    const float reach =
        c.orthographic ? 0.5f * c.ortho_scale * (1 + std::max(std::abs(c.shift_x), std::abs(c.shift_y))) : 0;
    if (!lt::within_traceable_range(c.xf.point(lt::Vec3(0.0f))) || !(reach <= lt::kTraceableRange))
      scene->scene.warnings.push_back(
          "the camera reaches beyond 1.8e18 from the origin, the range within which rays "
          "can be traced (Embree's); its rays from beyond it miss");
    begin_edit(scene, false);
    scene->scene.camera = c;
    scene->scene.camera_set = true;
  });
}

int lt_scene_set_world(lt_scene* scene, const lt_world_desc* d) {
  return guarded([&] {
    require(scene && d, "lt_scene_set_world: NULL argument");
    require(finite_array(d->color, 3) && std::isfinite(d->strength) && std::isfinite(d->rotation_z),
            "world colour, strength and rotation must be finite");
    require(d->image >= -1 && d->image < int(scene->scene.images.size()),
            "world refers to image " + std::to_string(d->image) + ", which does not exist");
    const lt::Vec3 color =
        lt::vmax(lt::Vec3(0.0f), lt::Vec3(d->color[0], d->color[1], d->color[2]) * std::max(0.0f, d->strength));
    std::shared_ptr<const lt::Program> program;
    if (d->image >= 0)
      program = std::make_shared<const lt::Program>(image_world_program(scene, d->image, d->rotation_z, color));
    begin_edit(scene);
    lt::World& w = scene->scene.world;
    if (program)
      w.set_program(std::move(program), 0);
    else
      w.set_color(color);
    w.camera_visible = (d->visibility & LT_VISIBLE_CAMERA) != 0;
    scene->scene.world_set = true;
  });
}

int lt_scene_set_world_program(lt_scene* scene, const lt_shader_program* p, int map_resolution, unsigned visibility) {
  return guarded([&] {
    require(scene && p, "lt_scene_set_world_program: NULL argument");
    require(map_resolution >= 0 && map_resolution <= 8192,
            "world map resolution " + std::to_string(map_resolution) + " is out of range (0 to 8192)");
    auto program = std::make_shared<const lt::Program>(to_program(scene, p));  // validated before anything changes
    begin_edit(scene);
    lt::World& w = scene->scene.world;
    w.set_program(std::move(program), map_resolution);
    w.camera_visible = (visibility & LT_VISIBLE_CAMERA) != 0;
    scene->scene.world_set = true;
  });
}

int lt_scene_set_world_lightgroup(lt_scene* scene, int lightgroup) {
  return guarded([&] {
    require(scene != nullptr, "lt_scene_set_world_lightgroup: NULL scene");
    require(lightgroup >= 0 && lightgroup <= kMaxLightgroups, "world light group out of range");
    begin_edit(scene);
    scene->scene.world.lightgroup = lightgroup - 1;
  });
}

int lt_scene_set_material_volume(lt_scene* scene, int material, const lt_volume_desc* d, int count, int null_surface) {
  return guarded([&] {
    require(scene && d, "lt_scene_set_material_volume: NULL argument");
    scene->scene.require_editable();
    lt::Scene& sc = scene->scene;
    require(material >= 0 && material < int(sc.materials.size()),
            "material " + std::to_string(material) + " does not exist");
    lt::VolumeMix c = to_volume_mix(d, count, false);
    sc.material_medium.resize(sc.materials.size(), -1);
    sc.material_null.resize(sc.materials.size(), 0);
    sc.media.push_back(homogeneous_medium(c));
    sc.material_medium[material] = int(sc.media.size()) - 1;
    sc.material_null[material] = null_surface != 0;
  });
}

int lt_scene_set_world_volume(lt_scene* scene, const lt_volume_desc* d, int count) {
  return guarded([&] {
    require(scene && d, "lt_scene_set_world_volume: NULL argument");
    scene->scene.require_editable();
    lt::VolumeMix c = to_volume_mix(d, count, false);
    lt::Scene& sc = scene->scene;
    sc.media.push_back(homogeneous_medium(c));
    if (!sc.media.back().empty() || sc.media.back().emissive()) sc.global_media.push_back(int(sc.media.size()) - 1);
  });
}

int lt_scene_add_volume_grid(lt_scene* scene, const char* path, const char* grid, const float transform[12], float step,
                             float clipping, float face_offset, const lt_volume_desc* d, int count, int* out_id) {
  return guarded([&] {
    require(scene && path && transform && d && out_id, "lt_scene_add_volume_grid: NULL argument");
    scene->scene.require_editable();
    lt::VolumeMix c = to_volume_mix(d, count, true);
    lt::Transform xf = to_transform(transform, "volume");
    require(std::abs(xf.determinant()) > 1e-30f, "volume transform is singular");
    require(std::isfinite(step) && step >= 0, "volume step must be finite and >= 0 (0: the voxel size)");
    require(std::isfinite(clipping) && clipping >= 0, "volume clipping must be finite and >= 0");
    require(std::isfinite(face_offset), "volume face offset must be finite");
    std::vector<std::string> emission_grids;
    const std::vector<lt::EmissionComponent> emission = grid_emission_components(d, count, &emission_grids);
    std::vector<std::string> names{grid && *grid ? grid : "density"};  // the density, then the emission's
    names.insert(names.end(), emission_grids.begin(), emission_grids.end());
    lt::Medium medium;
    try {
      std::vector<lt::GridData> loaded = lt::load_grids(path, names);
      std::vector<std::shared_ptr<const lt::GridData>> grids;
      for (lt::GridData& g : loaded) grids.push_back(std::make_shared<lt::GridData>(std::move(g)));
      medium = lt::Medium::heterogeneous(grids[0], c.sigma_a, c.sigma_s, c.phase.g[0], xf);
      if (!emission.empty()) {
        auto e = std::make_shared<lt::GridEmission>(
            std::vector<std::shared_ptr<const lt::GridData>>(grids.begin() + 1, grids.end()), emission,
            grids[0]->index_to_object);
        std::vector<const lt::GridData*> all;
        for (const auto& g : grids) all.push_back(g.get());
        e->set_region(lt::volume_mesh_region(all, clipping, face_offset));
        medium.set_grid_emission(std::move(e));
      }
    } catch (const lt::InvalidArgument& e) {
      throw lt::IoError(std::string(path) + ": " + e.what());  // a file that cannot be used is an I/O error
    }
    lt::Scene& sc = scene->scene;
    sc.media.push_back(std::move(medium));
    sc.media.back().set_phase(c.phase);
    if (step > 0) sc.media.back().set_march_step(step);
    *out_id = int(sc.media.size()) - 1;
    if (sc.media.back().empty() && !sc.media.back().emissive())  // an emission-only shader still emits
      sc.warnings.push_back(std::string(path) + ": volume has no density; left out");
    else
      sc.global_media.push_back(*out_id);
  });
}

namespace {
// The editable scene whose medium `volume` is a Volume object's grid (lt_scene_add_volume_grid's
// out_id), for the calls that set more of it.
lt::Scene& volume_grid_scene(lt_scene* scene, int volume, const char* call) {
  require(scene != nullptr, std::string(call) + ": NULL scene");
  scene->scene.require_editable();
  lt::Scene& sc = scene->scene;
  require(volume >= 0 && volume < int(sc.media.size()) && !sc.media[size_t(volume)].is_homogeneous(),
          "volume " + std::to_string(volume) + " is not a Volume object's grid");
  return sc;
}
}  // namespace

int lt_scene_set_volume_grid_lightgroup(lt_scene* scene, int volume, int lightgroup) {
  return guarded([&] {
    lt::Scene& sc = volume_grid_scene(scene, volume, "lt_scene_set_volume_grid_lightgroup");
    require(lightgroup >= 0 && lightgroup <= kMaxLightgroups, "volume light group out of range");
    sc.medium_groups.resize(sc.media.size(), -1);
    sc.medium_groups[size_t(volume)] = lightgroup - 1;
  });
}

int lt_scene_set_volume_grid_motion(lt_scene* scene, int volume, const float* transforms, int steps) {
  return guarded([&] {
    lt::Scene& sc = volume_grid_scene(scene, volume, "lt_scene_set_volume_grid_motion");
    require_motion_steps(steps, transforms, "volume");
    // Medium::set_motion refuses steps that are not finite or not invertible; none: still again.
    sc.media[size_t(volume)].set_motion(motion_transforms(transforms, steps));
  });
}

int lt_scene_commit(lt_scene* scene) {
  return guarded([&] {
    require(scene != nullptr, "lt_scene_commit: NULL scene");
    scene->scene.commit();
  });
}

void lt_render_settings_default(lt_render_settings* s) {
  if (!s) return;
  std::memset(s, 0, sizeof(*s));
  s->width = 640;
  s->height = 480;
  s->samples = 64;
  s->integrator = LT_INTEGRATOR_PATH;
  s->max_bounces = 12;
  s->diffuse_bounces = 4;
  s->glossy_bounces = 4;
  s->transmission_bounces = 12;
  s->transparent_bounces = 8;
  s->filter = LT_FILTER_BLACKMAN_HARRIS;
  s->filter_width = 1.5f;
  s->max_camera_length = 64;
  s->max_light_length = 64;
  s->mis_heuristic = LT_MIS_POWER;
  s->volume_bounces = 0;
  s->volume_estimator = LT_VOLUME_TRACKING;
  s->volume_step = 0;
  s->min_samples = 16;
  // Every pass but AO (its rays cost time) and Vector (it needs motion_pass).
  s->passes = ((1u << LT_PASS_COUNT) - 1) & ~((1u << LT_PASS_AO) | (1u << LT_PASS_VECTOR));
  s->caller_bytes = 0;
  s->sample_pattern = LT_PATTERN_SOBOL_OWEN;
  s->denoise = 0;
  s->mist_start = 5;
  s->mist_depth = 25;
  s->mist_falloff = 2;
  s->cryptomatte = 0;
  s->cryptomatte_levels = 6;
  s->pass_alpha_threshold = 0.5f;
  s->ao_distance = 10;
  s->motion_pass = 0;
  s->shadow_catcher_approximate = 1;
  s->denoise_start_sample = 0;
}

namespace {
std::string gib(double bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return b;
}
}  // namespace

int lt_render_start(lt_scene* scene, const lt_render_settings* s, lt_render** out) {
  return guarded([&] {
    require(scene && s && out, "lt_render_start: NULL argument");
    if (!scene->scene.committed()) throw lt::StateError("the scene must be committed before rendering");
    if (scene->scene.edited())
      throw lt::StateError("the scene was edited after its commit: commit it again before rendering");
    require(scene->scene.camera_set, "the scene has no camera");
    require(s->width > 0 && s->height > 0 && s->width <= kMaxDimension && s->height <= kMaxDimension &&
                (long long)s->width * s->height <= kMaxPixels,
            "resolution " + std::to_string(s->width) + "x" + std::to_string(s->height) + " is out of range (at most " +
                std::to_string(kMaxDimension) + " per side and " + std::to_string(kMaxPixels) + " pixels)");
    require(s->samples > 0 && s->samples <= (1 << 24), "samples must be in [1, 16777216]");
    require(s->sample_offset >= 0 && s->sample_offset <= (1 << 30) - s->samples,
            "sample offset must be in [0, 2^30 - samples]");
    bool full = s->border[0] == 0 && s->border[1] == 0 && s->border[2] == 0 && s->border[3] == 0;
    require(s->integrator >= 0 && s->integrator < LT_INTEGRATOR_COUNT,
            "unknown integrator " + std::to_string(s->integrator) +
                "; valid: " + lt::abi_enum_names("lt_integrator", "LT_INTEGRATOR_"));
    require(s->volume_bounces >= 0 && s->volume_bounces <= 1024, "volume bounces must be in [0, 1024]");
    require(s->volume_estimator == LT_VOLUME_RAY_MARCHING || s->volume_estimator == LT_VOLUME_TRACKING,
            "unknown volume estimator " + std::to_string(s->volume_estimator) + "; valid: RAY_MARCHING, TRACKING");
    require(std::isfinite(s->volume_step) && s->volume_step >= 0, "volume step must be finite and >= 0");
    require(
        s->integrator != LT_INTEGRATOR_BIDIRECTIONAL || (s->max_camera_length >= 1 && s->max_camera_length <= 1024 &&
                                                         s->max_light_length >= 0 && s->max_light_length <= 1024),
        "bidirectional path lengths must be in [1, 1024] (camera) and [0, 1024] (light)");
    require(s->strategy_view_depth >= 0 && s->strategy_view_depth <= 8, "strategy view depth must be in [0, 8]");
    if (s->integrator == LT_INTEGRATOR_BIDIRECTIONAL && s->strategy_view_depth > 0) {
      long long region =
          (long long)(full ? s->width : s->border[1] - s->border[0]) * (full ? s->height : s->border[3] - s->border[2]);
      long long cells = (long long)s->strategy_view_depth * (s->strategy_view_depth + 2);
      require(region * cells * 6 <= (1LL << 28), "the strategy view of " + std::to_string(cells) +
                                                     " images at this resolution needs more than 1 GiB; "
                                                     "lower the depth or the resolution");
    }
    require(s->mis_heuristic >= LT_MIS_POWER && s->mis_heuristic <= LT_MIS_UNIFORM,
            "unknown MIS heuristic " + std::to_string(s->mis_heuristic) + "; valid: POWER, BALANCE, UNIFORM");
    require(s->max_bounces >= 0 && s->diffuse_bounces >= 0 && s->glossy_bounces >= 0 && s->transmission_bounces >= 0 &&
                s->transparent_bounces >= 0 && s->max_bounces <= 1024,
            "bounce limits must be in [0, 1024]");
    require(std::isfinite(s->clamp_direct) && std::isfinite(s->clamp_indirect) && s->clamp_direct >= 0 &&
                s->clamp_indirect >= 0,
            "clamp values must be finite and >= 0");
    require(s->threads >= 0 && s->threads <= 4096, "threads must be in [0, 4096]");
    require(s->filter >= LT_FILTER_BOX && s->filter <= LT_FILTER_BLACKMAN_HARRIS, "unknown pixel filter");
    require(std::isfinite(s->filter_width) && s->filter_width > 0 && s->filter_width <= 100,
            "filter width must be in (0, 100]");
    require(std::isfinite(s->time_limit) && s->time_limit >= 0, "time limit must be finite and >= 0 (0: none)");
    require(std::isfinite(s->noise_target) && s->noise_target >= 0, "noise target must be finite and >= 0 (0: none)");
    require(!s->adaptive || s->noise_target > 0, "adaptive sampling needs a noise target > 0");
    require(s->min_samples >= 1 && s->min_samples <= (1 << 24), "min samples must be in [1, 16777216]");
    require((s->passes & ~((1u << LT_PASS_COUNT) - 1)) == 0, "passes has bits beyond LT_PASS_COUNT");
    require(std::isfinite(s->mist_start) && std::isfinite(s->mist_depth) && s->mist_depth >= 0 &&
                std::isfinite(s->mist_falloff) && s->mist_falloff >= 0,
            "mist start, depth and falloff must be finite, depth and falloff >= 0");
    require((s->cryptomatte & ~unsigned(LT_CRYPTOMATTE_OBJECT | LT_CRYPTOMATTE_MATERIAL | LT_CRYPTOMATTE_ASSET)) == 0,
            "cryptomatte has bits beyond LT_CRYPTOMATTE_ASSET");
    require(s->cryptomatte_levels >= 1 && s->cryptomatte_levels <= 16, "cryptomatte levels must be in [1, 16]");
    require(s->sample_pattern == LT_PATTERN_SOBOL_OWEN || s->sample_pattern == LT_PATTERN_INDEPENDENT,
            "unknown sample pattern " + std::to_string(s->sample_pattern) +
                "; valid: " + lt::abi_enum_names("lt_sample_pattern", "LT_PATTERN_"));
    lt::RenderSettings rs;
    rs.width = s->width;
    rs.height = s->height;
    if (full) {
      rs.x0 = 0;
      rs.y0 = 0;
      rs.x1 = s->width;
      rs.y1 = s->height;
    } else {
      require(s->border[0] >= 0 && s->border[0] < s->border[1] && s->border[1] <= s->width && s->border[2] >= 0 &&
                  s->border[2] < s->border[3] && s->border[3] <= s->height,
              "render border is outside the frame or empty");
      rs.x0 = s->border[0];
      rs.x1 = s->border[1];
      rs.y0 = s->border[2];
      rs.y1 = s->border[3];
    }
    rs.samples = s->samples;
    rs.seed = s->seed;
    rs.sample_offset = s->sample_offset;
    rs.integrator = lt::IntegratorType(s->integrator);
    auto& is = rs.integrator_settings;
    is.max_bounces = s->max_bounces;
    is.diffuse_bounces = s->diffuse_bounces;
    is.glossy_bounces = s->glossy_bounces;
    is.transmission_bounces = s->transmission_bounces;
    is.transparent_bounces = s->transparent_bounces;
    is.clamp_direct = s->clamp_direct;
    is.clamp_indirect = s->clamp_indirect;
    is.transparent_background = s->transparent_background != 0;
    is.max_camera_length = s->max_camera_length;
    is.max_light_length = s->max_light_length;
    is.mis = lt::MisHeuristic(s->mis_heuristic);
    is.volume_bounces = s->volume_bounces;
    is.volume_estimator = s->volume_estimator == LT_VOLUME_RAY_MARCHING ? lt::VolumeEstimator::RayMarching
                                                                        : lt::VolumeEstimator::Tracking;
    is.volume_step = s->volume_step;
    is.mist_start = s->mist_start;
    is.mist_depth = s->mist_depth;
    is.mist_falloff = s->mist_falloff;
    is.strategy_depth = s->integrator == LT_INTEGRATOR_BIDIRECTIONAL ? s->strategy_view_depth : 0;
    require(s->lightgroup_count >= 0 && s->lightgroup_count <= kMaxLightgroups &&
                (s->lightgroup_count == 0 || s->lightgroup_names),
            "light group count out of range (0 to 1024) or their names NULL");
    for (int g = 0; g < s->lightgroup_count; ++g) {
      require(s->lightgroup_names[g] != nullptr, "light group " + std::to_string(g) + " has no name");
      rs.lightgroup_names.emplace_back(s->lightgroup_names[g]);
    }
    is.lightgroups = s->lightgroup_count;
    require(
        s->aov_count >= 0 && s->aov_count <= kMaxLightgroups && (s->aov_count == 0 || (s->aov_names && s->aov_colors)),
        "AOV count out of range (0 to 1024) or their names or types NULL");
    for (int a = 0; a < s->aov_count; ++a) {
      require(s->aov_names[a] != nullptr, "AOV " + std::to_string(a) + " has no name");
      rs.aov_names.emplace_back(s->aov_names[a]);
      rs.aov_colors.push_back(s->aov_colors[a] != 0);
    }
    is.aovs = s->aov_count;
    require(std::isfinite(s->pass_alpha_threshold), "pass alpha threshold must be finite");
    is.pass_alpha_threshold = s->pass_alpha_threshold;
    require(std::isfinite(s->ao_distance) && s->ao_distance >= 0, "AO distance must be finite and >= 0");
    is.ao_distance = s->ao_distance;
    rs.motion_pass = s->motion_pass != 0;
    is.shadow_catcher_approximate = s->shadow_catcher_approximate != 0;
    // The integrators that split camera paths at catchers (the volume debug view does not).
    is.shadow_catcher = scene->scene.geometry.has_shadow_catcher() &&
                        (s->integrator == LT_INTEGRATOR_PATH || s->integrator == LT_INTEGRATOR_VOLPATH ||
                         s->integrator == LT_INTEGRATOR_BIDIRECTIONAL);
    rs.threads = s->threads;
    rs.filter = lt::FilterType(s->filter);
    rs.filter_width = s->filter_width;
    rs.time_limit = s->time_limit;
    rs.noise_target = s->noise_target;
    rs.adaptive = s->adaptive != 0;
    rs.min_samples = s->min_samples;
    rs.passes = s->passes;
    rs.pattern = lt::SamplePattern(s->sample_pattern);
    rs.denoise = s->denoise != 0;
    require(s->denoise_start_sample >= 0, "denoise start sample must be >= 0");
    rs.denoise_start_sample = s->denoise_start_sample;
    rs.cryptomatte = s->cryptomatte;  // lt_cryptomatte's bits are 1 << CryptomatteType
    rs.cryptomatte_levels = s->cryptomatte_levels;
    // Refuse before allocating, with what it would take, rather than fail (or be killed) later.
    const lt::MemoryEstimate need = lt::RenderJob::estimate_bytes(rs);
    const double total = double(need.total()) + double(s->caller_bytes);
    const size_t avail = lt::available_memory();
    if (total > double(avail))
      throw lt::OutOfMemory("a " + std::to_string(rs.x1 - rs.x0) + "x" + std::to_string(rs.y1 - rs.y0) +
                            " render needs about " + gib(total) + " (film " + gib(double(need.film)) +
                            ", other buffers " + gib(double(need.other)) + ", caller " + gib(double(s->caller_bytes)) +
                            ") but only " + gib(double(avail)) +
                            " is available; lower the resolution, render a border or fewer passes");
    auto r = std::make_unique<lt_render>();
    r->job = std::make_unique<lt::RenderJob>(scene->scene, rs);
    r->scene = scene;
    scene->live_renders.fetch_add(1);
    r->job->start();
    *out = r.release();
  });
}

int lt_render_poll(lt_render* render, lt_render_status* st) {
  return guarded([&] {
    require(render && st, "lt_render_poll: NULL argument");
    lt::RenderStatus s = render->job->status();
    st->state = int(s.state);
    st->samples_done = s.samples_done;
    st->samples_total = s.samples_total;
    st->elapsed_seconds = s.elapsed;
    st->remaining_seconds = s.remaining;
    st->nan_samples = s.nan_samples;
    st->rays = s.rays;
    st->rel_error = s.rel_error;
    st->halt_reason = int(s.halt_reason);
    st->active_pixels = s.active_pixels;
    st->unestimated_pixels = s.unestimated_pixels;
    st->denoised = s.denoised ? 1 : 0;
    st->denoise_seconds = s.denoise_seconds;
  });
}

int lt_render_cancel(lt_render* render) {
  return guarded([&] {
    require(render != nullptr, "lt_render_cancel: NULL render");
    render->job->cancel();
  });
}

int lt_render_wait(lt_render* render) {
  return guarded([&] {
    require(render != nullptr, "lt_render_wait: NULL render");
    render->job->wait();
    if (render->job->status().state == lt::RenderState::Failed) {
      const std::string what = std::string("render failed: ") + render->job->error();
      if (render->job->out_of_memory()) throw lt::OutOfMemory(what);
      throw std::runtime_error(what);
    }
  });
}

int lt_pass_channels(int pass) {
  if (pass < 0 || pass >= LT_PASS_COUNT) return 0;
  return lt::pass_channels(lt::Pass(pass));
}

namespace {
void read_pass_rows(lt_render* render, int pass, int y0, int rows, float* out, size_t float_count) {
  require(render && out, "lt_render_read_pass: NULL argument");
  require(pass >= 0 && pass < LT_PASS_COUNT, "unknown pass " + std::to_string(pass));
  const auto& film = render->job->film();
  if (rows < 0) rows = film.height();  // every row
  require(y0 >= 0 && y0 <= film.height() - rows, "rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                                                     " are not within the " + std::to_string(film.height()) +
                                                     " rows of the render region");
  size_t need = size_t(film.width()) * rows * lt::pass_channels(lt::Pass(pass));
  require(float_count == need,
          "pass buffer holds " + std::to_string(float_count) + " floats; " + std::to_string(need) + " are needed");
  film.read_rows(lt::Pass(pass), y0, rows, out);
}

// Rows [y0, y0 + rows) of the strategy grid (rows < 0: all); out NULL: only the grid's size.
void read_strategy_rows(lt_render* render, int y0, int rows, float* out, size_t float_count, int* width, int* height) {
  require(render != nullptr, "lt_render_read_strategy_grid: NULL argument");
  const lt::RenderJob& job = *render->job;
  const int depth = job.settings().integrator_settings.strategy_depth;
  if (depth <= 0) throw lt::StateError("this render has no strategy view (bidirectional with strategy_view_depth > 0)");
  const int columns = lt::strategy_columns(depth);
  *width = columns * job.region_width();
  *height = depth * job.region_height();
  if (!out) return;
  if (rows < 0) rows = *height;
  require(y0 >= 0 && y0 <= *height - rows, "rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                                               " are not within the strategy grid's " + std::to_string(*height));
  if (job.status().state == lt::RenderState::Running)
    throw lt::StateError("the strategy view can be read once the render has stopped");
  size_t need = size_t(*width) * rows * 3;
  require(float_count == need, "strategy grid buffer holds " + std::to_string(float_count) + " floats; " +
                                   std::to_string(need) + " are needed");
  job.film().read_strategy_grid(columns, depth, out, y0, rows);
}
}  // namespace

int lt_render_read_lightgroup_rows(lt_render* render, int group, int y0, int rows, float* out, size_t float_count) {
  return guarded([&] {
    require(render && out, "lt_render_read_lightgroup_rows: NULL argument");
    const auto& film = render->job->film();
    require(rows >= 0 && y0 >= 0 && y0 <= film.height() - rows,
            "rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) + " are not within the " +
                std::to_string(film.height()) + " rows of the render region");
    const size_t need = size_t(film.width()) * rows * 3;
    require(float_count == need, "light group buffer holds " + std::to_string(float_count) + " floats; " +
                                     std::to_string(need) + " are needed");
    film.read_lightgroup_rows(group, y0, rows, out);
  });
}

int lt_render_read_aov_rows(lt_render* render, int index, int y0, int rows, float* out, size_t float_count) {
  return guarded([&] {
    require(render && out, "lt_render_read_aov_rows: NULL argument");
    const auto& job = *render->job;
    const auto& film = job.film();
    require(index >= 0 && index < film.aovs(),
            "AOV " + std::to_string(index) + " is not one of the render's " + std::to_string(film.aovs()));
    require(rows >= 0 && y0 >= 0 && y0 <= film.height() - rows,
            "rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) + " are not within the " +
                std::to_string(film.height()) + " rows of the render region");
    const int channels = job.settings().aov_colors[size_t(index)] ? 4 : 1;
    const size_t need = size_t(film.width()) * rows * channels;
    require(float_count == need,
            "AOV buffer holds " + std::to_string(float_count) + " floats; " + std::to_string(need) + " are needed");
    film.read_aov_rows(index, channels, y0, rows, out);
  });
}

int lt_render_read_pass(lt_render* render, int pass, float* out, size_t float_count) {
  return guarded([&] { read_pass_rows(render, pass, 0, -1, out, float_count); });
}

int lt_render_read_pass_rows(lt_render* render, int pass, int y0, int rows, float* out, size_t float_count) {
  return guarded([&] {
    require(rows >= 0, "lt_render_read_pass_rows: negative row count");
    read_pass_rows(render, pass, y0, rows, out, float_count);
  });
}

int lt_render_read_cryptomatte_rows(lt_render* render, int type, int layer, int y0, int rows, float* out,
                                    size_t float_count) {
  return guarded([&] {
    require(render && out, "lt_render_read_cryptomatte_rows: NULL argument");
    require(type == LT_CRYPTOMATTE_OBJECT || type == LT_CRYPTOMATTE_MATERIAL || type == LT_CRYPTOMATTE_ASSET,
            "unknown Cryptomatte type " + std::to_string(type) +
                "; valid: " + lt::abi_enum_names("lt_cryptomatte", "LT_CRYPTOMATTE_"));
    const auto& film = render->job->film();
    require(rows >= 0 && y0 >= 0 && y0 <= film.height() - rows,
            "rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) + " are not within the " +
                std::to_string(film.height()) + " rows of the render region");
    const size_t need = size_t(film.width()) * rows * 4;
    require(float_count == need, "Cryptomatte buffer holds " + std::to_string(float_count) + " floats; " +
                                     std::to_string(need) + " are needed");
    film.read_cryptomatte_rows(type == LT_CRYPTOMATTE_OBJECT     ? lt::kCryptoObject
                               : type == LT_CRYPTOMATTE_MATERIAL ? lt::kCryptoMaterial
                                                                 : lt::kCryptoAsset,
                               layer, y0, rows, out);
  });
}

int lt_render_read_strategy_grid(lt_render* render, float* out, size_t float_count, int* width, int* height) {
  return guarded([&] {
    require(width && height, "lt_render_read_strategy_grid: NULL argument");
    read_strategy_rows(render, 0, -1, out, float_count, width, height);
  });
}

int lt_render_read_strategy_grid_rows(lt_render* render, int y0, int rows, float* out, size_t float_count) {
  return guarded([&] {
    require(out != nullptr, "lt_render_read_strategy_grid_rows: NULL argument");
    require(rows >= 0, "lt_render_read_strategy_grid_rows: negative row count");
    int width = 0, height = 0;
    read_strategy_rows(render, y0, rows, out, float_count, &width, &height);
  });
}

void lt_render_destroy(lt_render* render) { delete render; }

int lt_render_write_exr(lt_render* render, const char* path) {
  return guarded([&] {
    require(render && path, "lt_render_write_exr: NULL argument");
    lt::write_render_exr(path, *render->job);
  });
}

int lt_render_write_exr_attributes(lt_render* render, const char* path, const char* const* attributes) {
  return guarded([&] {
    require(render && path, "lt_render_write_exr_attributes: NULL argument");
    std::map<std::string, std::string> extra;
    for (const char* const* a = attributes; a && a[0]; a += 2) {
      require(a[1] != nullptr, std::string("EXR attribute ") + a[0] + " has no value");
      require(*a[0] != '\0', "EXR attribute names must not be empty");
      extra[a[0]] = a[1];
    }
    lt::write_render_exr(path, *render->job, extra);
  });
}

int lt_merge_exr(const char* out_path, const char* const* part_paths, int part_count) {
  return guarded([&] {
    require(out_path && (part_paths || part_count == 0), "lt_merge_exr: NULL argument");
    require(part_count > 0, "lt_merge_exr: no parts to merge");
    std::vector<std::string> parts;
    for (int i = 0; i < part_count; ++i) {
      require(part_paths[i] != nullptr, "lt_merge_exr: part path " + std::to_string(i) + " is NULL");
      parts.push_back(part_paths[i]);
    }
    lt::merge_exr(out_path, parts);
  });
}

}  // extern "C"
