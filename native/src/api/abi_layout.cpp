// lt_abi_layout: lantern.h's structs and enums as compiled, so that a hand-written binding (the
// add-on's ctypes declarations) is checked against the library it loads instead of trusted.
#include "api/abi_layout.h"

#include <cstddef>
#include <cstring>

#include "lantern/lantern.h"

namespace {

#define LT_STRUCT(T) \
  { #T, nullptr, (long long)sizeof(T), 0 }
#define LT_FIELD(T, f) \
  { #T, #f, (long long)offsetof(T, f), (long long)sizeof(T::f) }
#define LT_CONST(E, c) \
  { #E, #c, (long long)(c), 0 }

const lt_abi_entry kLayout[] = {
    LT_STRUCT(lt_abi_entry),
    LT_FIELD(lt_abi_entry, type),
    LT_FIELD(lt_abi_entry, field),
    LT_FIELD(lt_abi_entry, value),
    LT_FIELD(lt_abi_entry, size),

    LT_CONST(lt_status, LT_OK),
    LT_CONST(lt_status, LT_ERROR_INVALID_ARGUMENT),
    LT_CONST(lt_status, LT_ERROR_OUT_OF_MEMORY),
    LT_CONST(lt_status, LT_ERROR_IO),
    LT_CONST(lt_status, LT_ERROR_STATE),
    LT_CONST(lt_status, LT_ERROR_INTERNAL),

    LT_CONST(lt_interpolation, LT_INTERP_LINEAR),
    LT_CONST(lt_interpolation, LT_INTERP_CLOSEST),
    LT_CONST(lt_extension, LT_EXTENSION_REPEAT),
    LT_CONST(lt_extension, LT_EXTENSION_EXTEND),
    LT_CONST(lt_extension, LT_EXTENSION_CLIP),
    LT_STRUCT(lt_image_desc),
    LT_FIELD(lt_image_desc, width),
    LT_FIELD(lt_image_desc, height),
    LT_FIELD(lt_image_desc, channels),
    LT_FIELD(lt_image_desc, pixels),
    LT_FIELD(lt_image_desc, srgb),
    LT_FIELD(lt_image_desc, interpolation),
    LT_FIELD(lt_image_desc, extension),
    LT_FIELD(lt_image_desc, alpha),
    LT_CONST(lt_image_alpha, LT_ALPHA_IGNORE),
    LT_CONST(lt_image_alpha, LT_ALPHA_STRAIGHT),
    LT_CONST(lt_image_alpha, LT_ALPHA_PREMULTIPLIED),
    LT_CONST(lt_image_alpha, LT_ALPHA_CHANNEL_PACKED),

    LT_STRUCT(lt_shader_program),
    LT_FIELD(lt_shader_program, code),
    LT_FIELD(lt_shader_program, code_words),
    LT_FIELD(lt_shader_program, constants),
    LT_FIELD(lt_shader_program, constant_count),
    LT_FIELD(lt_shader_program, registers),

    LT_STRUCT(lt_mesh_desc),
    LT_FIELD(lt_mesh_desc, positions),
    LT_FIELD(lt_mesh_desc, vertex_count),
    LT_FIELD(lt_mesh_desc, triangles),
    LT_FIELD(lt_mesh_desc, triangle_count),
    LT_FIELD(lt_mesh_desc, corner_normals),
    LT_FIELD(lt_mesh_desc, corner_uvs),
    LT_FIELD(lt_mesh_desc, material_slots),
    LT_FIELD(lt_mesh_desc, texspace_location),
    LT_FIELD(lt_mesh_desc, texspace_size),
    LT_FIELD(lt_mesh_desc, attributes),
    LT_FIELD(lt_mesh_desc, attribute_count),
    LT_STRUCT(lt_mesh_attribute),
    LT_FIELD(lt_mesh_attribute, id),
    LT_FIELD(lt_mesh_attribute, components),
    LT_FIELD(lt_mesh_attribute, values),
    LT_FIELD(lt_mesh_attribute, value_count),

    LT_CONST(lt_visibility, LT_VISIBLE_CAMERA),
    LT_CONST(lt_visibility, LT_VISIBLE_DIFFUSE),
    LT_CONST(lt_visibility, LT_VISIBLE_GLOSSY),
    LT_CONST(lt_visibility, LT_VISIBLE_TRANSMISSION),
    LT_CONST(lt_visibility, LT_VISIBLE_SHADOW),
    LT_CONST(lt_visibility, LT_VISIBLE_ALL),
    LT_STRUCT(lt_instance_desc),
    LT_FIELD(lt_instance_desc, mesh),
    LT_FIELD(lt_instance_desc, transform),
    LT_FIELD(lt_instance_desc, materials),
    LT_FIELD(lt_instance_desc, material_count),
    LT_FIELD(lt_instance_desc, visibility),
    LT_FIELD(lt_instance_desc, color),
    LT_FIELD(lt_instance_desc, pass_index),
    LT_FIELD(lt_instance_desc, random_id),
    LT_FIELD(lt_instance_desc, attribute_ids),
    LT_FIELD(lt_instance_desc, attribute_values),
    LT_FIELD(lt_instance_desc, attribute_count),

    LT_CONST(lt_light_type, LT_LIGHT_POINT),
    LT_CONST(lt_light_type, LT_LIGHT_SPOT),
    LT_CONST(lt_light_type, LT_LIGHT_AREA),
    LT_CONST(lt_light_type, LT_LIGHT_SUN),
    LT_CONST(lt_area_shape, LT_AREA_SQUARE),
    LT_CONST(lt_area_shape, LT_AREA_RECTANGLE),
    LT_CONST(lt_area_shape, LT_AREA_DISK),
    LT_CONST(lt_area_shape, LT_AREA_ELLIPSE),
    LT_STRUCT(lt_light_desc),
    LT_FIELD(lt_light_desc, type),
    LT_FIELD(lt_light_desc, color),
    LT_FIELD(lt_light_desc, transform),
    LT_FIELD(lt_light_desc, radius),
    LT_FIELD(lt_light_desc, spot_size),
    LT_FIELD(lt_light_desc, spot_blend),
    LT_FIELD(lt_light_desc, shape),
    LT_FIELD(lt_light_desc, size_x),
    LT_FIELD(lt_light_desc, size_y),
    LT_FIELD(lt_light_desc, angle),
    LT_FIELD(lt_light_desc, visibility),

    LT_CONST(lt_camera_type, LT_CAMERA_PERSPECTIVE),
    LT_CONST(lt_camera_type, LT_CAMERA_ORTHOGRAPHIC),
    LT_CONST(lt_sensor_fit, LT_SENSOR_AUTO),
    LT_CONST(lt_sensor_fit, LT_SENSOR_HORIZONTAL),
    LT_CONST(lt_sensor_fit, LT_SENSOR_VERTICAL),
    LT_STRUCT(lt_camera_desc),
    LT_FIELD(lt_camera_desc, type),
    LT_FIELD(lt_camera_desc, transform),
    LT_FIELD(lt_camera_desc, focal_length),
    LT_FIELD(lt_camera_desc, sensor_width),
    LT_FIELD(lt_camera_desc, sensor_height),
    LT_FIELD(lt_camera_desc, sensor_fit),
    LT_FIELD(lt_camera_desc, ortho_scale),
    LT_FIELD(lt_camera_desc, shift_x),
    LT_FIELD(lt_camera_desc, shift_y),
    LT_FIELD(lt_camera_desc, clip_start),
    LT_FIELD(lt_camera_desc, clip_end),
    LT_FIELD(lt_camera_desc, pixel_aspect),

    LT_STRUCT(lt_world_desc),
    LT_FIELD(lt_world_desc, color),
    LT_FIELD(lt_world_desc, strength),
    LT_FIELD(lt_world_desc, image),
    LT_FIELD(lt_world_desc, rotation_z),
    LT_FIELD(lt_world_desc, visibility),

    LT_CONST(lt_volume_node, LT_VOLUME_PRINCIPLED),
    LT_CONST(lt_volume_node, LT_VOLUME_SCATTER),
    LT_CONST(lt_volume_node, LT_VOLUME_ABSORPTION),
    LT_CONST(lt_volume_node, LT_VOLUME_EMISSION),
    LT_STRUCT(lt_volume_desc),
    LT_FIELD(lt_volume_desc, node),
    LT_FIELD(lt_volume_desc, color),
    LT_FIELD(lt_volume_desc, density),
    LT_FIELD(lt_volume_desc, absorption_color),
    LT_FIELD(lt_volume_desc, anisotropy),
    LT_FIELD(lt_volume_desc, emission_strength),
    LT_FIELD(lt_volume_desc, emission_color),
    LT_FIELD(lt_volume_desc, blackbody_intensity),
    LT_FIELD(lt_volume_desc, blackbody_tint),
    LT_FIELD(lt_volume_desc, temperature),

    LT_STRUCT(lt_scene_stats),
    LT_FIELD(lt_scene_stats, mesh_bvh_builds),
    LT_FIELD(lt_scene_stats, top_bvh_builds),
    LT_FIELD(lt_scene_stats, light_sampler_builds),
    LT_FIELD(lt_scene_stats, emissive_triangles),
    LT_FIELD(lt_scene_stats, emissive_instances),
    LT_FIELD(lt_scene_stats, image_bytes),
    LT_FIELD(lt_scene_stats, image_texels),
    LT_FIELD(lt_scene_stats, byte_images),
    LT_FIELD(lt_scene_stats, world_map_width),
    LT_FIELD(lt_scene_stats, world_map_height),

    LT_CONST(lt_integrator, LT_INTEGRATOR_PATH),
    LT_CONST(lt_integrator, LT_INTEGRATOR_BIDIRECTIONAL),
    LT_CONST(lt_integrator, LT_INTEGRATOR_VOLPATH),
    LT_CONST(lt_integrator, LT_INTEGRATOR_VOLUME_DEBUG),
    LT_CONST(lt_integrator, LT_INTEGRATOR_COUNT),
    LT_CONST(lt_volume_estimator, LT_VOLUME_RAY_MARCHING),
    LT_CONST(lt_volume_estimator, LT_VOLUME_TRACKING),
    LT_CONST(lt_mis, LT_MIS_POWER),
    LT_CONST(lt_mis, LT_MIS_BALANCE),
    LT_CONST(lt_mis, LT_MIS_UNIFORM),
    LT_CONST(lt_filter, LT_FILTER_BOX),
    LT_CONST(lt_filter, LT_FILTER_GAUSSIAN),
    LT_CONST(lt_filter, LT_FILTER_BLACKMAN_HARRIS),
    LT_STRUCT(lt_render_settings),
    LT_FIELD(lt_render_settings, width),
    LT_FIELD(lt_render_settings, height),
    LT_FIELD(lt_render_settings, border),
    LT_FIELD(lt_render_settings, samples),
    LT_FIELD(lt_render_settings, seed),
    LT_FIELD(lt_render_settings, sample_offset),
    LT_FIELD(lt_render_settings, integrator),
    LT_FIELD(lt_render_settings, max_bounces),
    LT_FIELD(lt_render_settings, diffuse_bounces),
    LT_FIELD(lt_render_settings, glossy_bounces),
    LT_FIELD(lt_render_settings, transmission_bounces),
    LT_FIELD(lt_render_settings, transparent_bounces),
    LT_FIELD(lt_render_settings, clamp_direct),
    LT_FIELD(lt_render_settings, clamp_indirect),
    LT_FIELD(lt_render_settings, threads),
    LT_FIELD(lt_render_settings, filter),
    LT_FIELD(lt_render_settings, filter_width),
    LT_FIELD(lt_render_settings, transparent_background),
    LT_FIELD(lt_render_settings, max_camera_length),
    LT_FIELD(lt_render_settings, max_light_length),
    LT_FIELD(lt_render_settings, mis_heuristic),
    LT_FIELD(lt_render_settings, strategy_view_depth),
    LT_FIELD(lt_render_settings, volume_bounces),
    LT_FIELD(lt_render_settings, volume_estimator),
    LT_FIELD(lt_render_settings, volume_step),
    LT_FIELD(lt_render_settings, time_limit),
    LT_FIELD(lt_render_settings, noise_target),
    LT_FIELD(lt_render_settings, adaptive),
    LT_FIELD(lt_render_settings, min_samples),
    LT_FIELD(lt_render_settings, passes),
    LT_FIELD(lt_render_settings, caller_bytes),

    LT_CONST(lt_render_state, LT_STATE_RUNNING),
    LT_CONST(lt_render_state, LT_STATE_DONE),
    LT_CONST(lt_render_state, LT_STATE_CANCELLED),
    LT_CONST(lt_render_state, LT_STATE_FAILED),
    LT_STRUCT(lt_render_status),
    LT_FIELD(lt_render_status, state),
    LT_FIELD(lt_render_status, samples_done),
    LT_FIELD(lt_render_status, samples_total),
    LT_FIELD(lt_render_status, elapsed_seconds),
    LT_FIELD(lt_render_status, remaining_seconds),
    LT_FIELD(lt_render_status, nan_samples),
    LT_FIELD(lt_render_status, rays),
    LT_FIELD(lt_render_status, rel_error),
    LT_FIELD(lt_render_status, halt_reason),
    LT_FIELD(lt_render_status, active_pixels),
    LT_FIELD(lt_render_status, unestimated_pixels),
    LT_CONST(lt_halt_reason, LT_HALT_NONE),
    LT_CONST(lt_halt_reason, LT_HALT_SAMPLES),
    LT_CONST(lt_halt_reason, LT_HALT_TIME_LIMIT),
    LT_CONST(lt_halt_reason, LT_HALT_NOISE_TARGET),
    LT_CONST(lt_halt_reason, LT_HALT_CANCELLED),
    LT_CONST(lt_halt_reason, LT_HALT_FAILED),

    LT_CONST(lt_pass, LT_PASS_COMBINED),
    LT_CONST(lt_pass, LT_PASS_DEPTH),
    LT_CONST(lt_pass, LT_PASS_NORMAL),
    LT_CONST(lt_pass, LT_PASS_ALBEDO),
    LT_CONST(lt_pass, LT_PASS_VARIANCE),
    LT_CONST(lt_pass, LT_PASS_SAMPLE_COUNT),
    LT_CONST(lt_pass, LT_PASS_COUNT),
};

#undef LT_STRUCT
#undef LT_FIELD
#undef LT_CONST

}  // namespace

std::string lt::abi_enum_names(const char* type, const char* prefix) {
  std::string out;
  const size_t n = std::strlen(prefix);
  for (const lt_abi_entry& e : kLayout) {
    if (!e.field || std::strcmp(e.type, type) != 0 || std::strncmp(e.field, prefix, n) != 0) continue;
    if (std::strcmp(e.field + n, "COUNT") == 0) continue;
    out += (out.empty() ? "" : ", ") + std::string(e.field + n);
  }
  return out;
}

extern "C" const lt_abi_entry* lt_abi_layout(int* count) {
  if (count) *count = int(sizeof kLayout / sizeof kLayout[0]);
  return kLayout;
}
