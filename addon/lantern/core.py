"""ctypes binding of Lantern's C ABI (native/include/lantern/lantern.h).

This is the only module that knows the ABI: structures, signatures and status codes live here.
Bulk arrays are numpy contiguous float32/int32 passed by pointer; the core copies what it keeps.

The declarations below are Python's spelling of lantern.h, checked against the library when it
loads (lt_abi_layout: every struct's size, every field's offset and size, every constant's value):
a library built from another lantern.h is refused with a message naming what differs. Enum names
(integrators, ...) and render-setting defaults are read from the core, not repeated here.
"""

import ctypes
import math
import os
import threading

import numpy as np

ABI_VERSION = 27

# lt_status
OK = 0
ERROR_INVALID_ARGUMENT, ERROR_OUT_OF_MEMORY, ERROR_IO, ERROR_STATE, ERROR_INTERNAL = 1, 2, 3, 4, 5
_STATUS_NAMES = {
    1: "invalid argument",
    2: "out of memory",
    3: "I/O error",
    4: "invalid state",
    5: "internal error",
}

# lt_interpolation, lt_extension
INTERP_LINEAR, INTERP_CLOSEST, INTERP_CUBIC = 0, 1, 2
EXTENSION_REPEAT, EXTENSION_EXTEND, EXTENSION_CLIP = 0, 1, 2
# lt_displacement_method (Cycles' Material > Settings > Displacement).
DISPLACEMENT_BUMP, DISPLACEMENT_TRUE, DISPLACEMENT_BOTH = 0, 1, 2
ALPHA_IGNORE, ALPHA_STRAIGHT, ALPHA_PREMULTIPLIED, ALPHA_CHANNEL_PACKED = 0, 1, 2, 3

# lt_node_type
# lt_visibility
VISIBLE_CAMERA = 1
VISIBLE_DIFFUSE = 2
VISIBLE_GLOSSY = 4
VISIBLE_TRANSMISSION = 8
VISIBLE_SHADOW = 16
VISIBLE_ALL = 31

# lt_light_type, lt_area_shape
LIGHT_POINT, LIGHT_SPOT, LIGHT_AREA, LIGHT_SUN = 0, 1, 2, 3
AREA_SQUARE, AREA_RECTANGLE, AREA_DISK, AREA_ELLIPSE = 0, 1, 2, 3

# lt_camera_type, lt_sensor_fit, lt_panorama_type
CAMERA_PERSPECTIVE, CAMERA_ORTHOGRAPHIC, CAMERA_PANORAMA = 0, 1, 2
SENSOR_AUTO, SENSOR_HORIZONTAL, SENSOR_VERTICAL = 0, 1, 2
PANORAMA_EQUIRECTANGULAR, PANORAMA_FISHEYE_EQUIDISTANT, PANORAMA_FISHEYE_EQUISOLID = 0, 1, 2
PANORAMA_MIRRORBALL, PANORAMA_FISHEYE_LENS_POLYNOMIAL, PANORAMA_EQUIANGULAR_CUBEMAP_FACE = 3, 4, 5
# Cycles' default lens polynomial k0 .. k4 (cycles/camera.py: a 50 mm lens on a 36 mm sensor).
FISHEYE_POLYNOMIAL_DEFAULT = (-1.1735143712967577e-05, -0.019988736953434998, -3.3525322965709175e-06,
                              3.099275275886036e-06, -2.6064646454854524e-08)

# lt_integrator: by name from the core (enum_value("lt_integrator", "PATH"), enum_names).
# lt_volume_estimator, lt_volume_node
VOLUME_RAY_MARCHING, VOLUME_TRACKING = 0, 1
VOLUME_PRINCIPLED, VOLUME_SCATTER, VOLUME_ABSORPTION, VOLUME_EMISSION = 0, 1, 2, 3
MIS_POWER, MIS_BALANCE, MIS_UNIFORM = 0, 1, 2
FILTER_BOX, FILTER_GAUSSIAN, FILTER_BLACKMAN_HARRIS = 0, 1, 2
PATTERN_SOBOL_OWEN, PATTERN_INDEPENDENT = 0, 1

# lt_render_state
STATE_RUNNING, STATE_DONE, STATE_CANCELLED, STATE_FAILED = 0, 1, 2, 3
# lt_halt_reason
HALT_NONE, HALT_SAMPLES, HALT_TIME_LIMIT, HALT_NOISE_TARGET, HALT_CANCELLED, HALT_FAILED = range(6)
HALT_NAMES = ("running", "samples", "time limit", "noise target", "cancelled", "failed")

# lt_pass
PASS_COMBINED = 0
PASS_DEPTH = 1
PASS_NORMAL = 2
PASS_ALBEDO = 3
PASS_VARIANCE = 4
PASS_SAMPLE_COUNT = 5
PASS_NOISY_IMAGE = 6
PASS_DENOISING_NORMAL = 7
PASS_DENOISING_ALBEDO = 8
PASS_DENOISING_DEPTH = 9
PASS_DIFFUSE_DIRECT = 10
PASS_DIFFUSE_INDIRECT = 11
PASS_DIFFUSE_COLOR = 12
PASS_GLOSSY_DIRECT = 13
PASS_GLOSSY_INDIRECT = 14
PASS_GLOSSY_COLOR = 15
PASS_TRANSMISSION_DIRECT = 16
PASS_TRANSMISSION_INDIRECT = 17
PASS_TRANSMISSION_COLOR = 18
PASS_VOLUME_DIRECT = 19
PASS_VOLUME_INDIRECT = 20
PASS_EMISSION = 21
PASS_ENVIRONMENT = 22
PASS_POSITION = 23
PASS_UV = 24
PASS_MIST = 25
PASS_OBJECT_INDEX = 26
PASS_MATERIAL_INDEX = 27
PASS_AO = 28
PASS_VECTOR = 29
PASS_SHADOW_CATCHER = 30
PASS_COUNT = 31
# lt_cryptomatte (bits of lt_render_settings.cryptomatte)
CRYPTOMATTE_OBJECT, CRYPTOMATTE_MATERIAL, CRYPTOMATTE_ASSET = 1, 2, 4


class LanternError(RuntimeError):
    """A failing Lantern call; `status` is the lt_status code, the message lt_last_error()."""

    def __init__(self, message, status=None, detail=None):
        super().__init__(message)
        self.status = status
        self.detail = detail or message  # lt_last_error() alone, without the call's name


# ---- structures (field order and types exactly as in lantern.h; _c_name_ names the C struct) -----

_f_p = ctypes.POINTER(ctypes.c_float)
_i_p = ctypes.POINTER(ctypes.c_int)


class ImageDesc(ctypes.Structure):
    _c_name_ = "lt_image_desc"
    _fields_ = [
        ("width", ctypes.c_int),
        ("height", ctypes.c_int),
        ("channels", ctypes.c_int),
        ("pixels", _f_p),
        ("srgb", ctypes.c_int),
        ("interpolation", ctypes.c_int),
        ("extension", ctypes.c_int),
        ("alpha", ctypes.c_int),
        ("ocio_config", ctypes.c_char_p),
        ("ocio_space", ctypes.c_char_p),
    ]


class ImageFileDesc(ctypes.Structure):
    _c_name_ = "lt_image_file_desc"
    _fields_ = [
        ("path", ctypes.c_char_p),
        ("color_space", ctypes.c_int),
        ("alpha_mode", ctypes.c_int),
        ("use_alpha", ctypes.c_int),
        ("interpolation", ctypes.c_int),
        ("extension", ctypes.c_int),
        ("ocio_config", ctypes.c_char_p),
        ("ocio_space", ctypes.c_char_p),
    ]


class ShaderProgram(ctypes.Structure):
    _c_name_ = "lt_shader_program"
    _fields_ = [
        ("code", ctypes.POINTER(ctypes.c_uint32)),
        ("code_words", ctypes.c_int),
        ("constants", _f_p),
        ("constant_count", ctypes.c_int),
        ("registers", ctypes.c_int),
    ]


def _program(program):
    """An lt_shader_program over (code, constants, registers), and the arrays it points into."""
    code, constants, registers = program
    c = np.ascontiguousarray(np.asarray(code, dtype=np.uint32).reshape(-1))
    k = np.ascontiguousarray(np.asarray(constants, dtype=np.float32).reshape(-1))
    d = ShaderProgram(c.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)), c.size, _fptr(k) if k.size else None,
                      k.size, int(registers))
    return d, (c, k)


class MeshAttribute(ctypes.Structure):
    _c_name_ = "lt_mesh_attribute"
    _fields_ = [
        ("id", ctypes.c_int),
        ("components", ctypes.c_int),
        ("values", _f_p),
        ("value_count", ctypes.c_int),
    ]


class MeshDesc(ctypes.Structure):
    _c_name_ = "lt_mesh_desc"
    _fields_ = [
        ("positions", _f_p),
        ("vertex_count", ctypes.c_int),
        ("triangles", _i_p),
        ("triangle_count", ctypes.c_int),
        ("corner_normals", _f_p),
        ("corner_uvs", _f_p),
        ("material_slots", _i_p),
        ("texspace_location", ctypes.c_float * 3),
        ("texspace_size", ctypes.c_float * 3),
        ("attributes", ctypes.POINTER(MeshAttribute)),
        ("attribute_count", ctypes.c_int),
        ("motion_positions", _f_p),
        ("motion_corner_normals", _f_p),
        ("motion_step_count", ctypes.c_int),
        ("flat_triangles", ctypes.POINTER(ctypes.c_uint8)),
    ]


class CurvesAttribute(ctypes.Structure):
    _c_name_ = "lt_curves_attribute"
    _fields_ = [
        ("id", ctypes.c_int),
        ("components", ctypes.c_int),
        ("per_point", ctypes.c_int),
        ("values", _f_p),
        ("value_count", ctypes.c_int),
    ]


class CurvesDesc(ctypes.Structure):
    _c_name_ = "lt_curves_desc"
    _fields_ = [
        ("points", _f_p),
        ("point_count", ctypes.c_uint32),
        ("curve_offsets", ctypes.POINTER(ctypes.c_uint32)),
        ("curve_count", ctypes.c_uint32),
        ("material_slots", _i_p),
        ("motion_points", _f_p),
        ("motion_step_count", ctypes.c_int),
        ("curve_uvs", _f_p),
        ("generated_from_root", ctypes.c_int),
        ("texspace_location", ctypes.c_float * 3),
        ("texspace_size", ctypes.c_float * 3),
        ("attributes", ctypes.POINTER(CurvesAttribute)),
        ("attribute_count", ctypes.c_int),
    ]


class InstanceDesc(ctypes.Structure):
    _c_name_ = "lt_instance_desc"
    _fields_ = [
        ("mesh", ctypes.c_int),
        ("transform", ctypes.c_float * 12),
        ("materials", _i_p),
        ("material_count", ctypes.c_int),
        ("visibility", ctypes.c_uint),
        ("color", ctypes.c_float * 4),
        ("pass_index", ctypes.c_int),
        ("random_id", ctypes.c_uint32),
        ("attribute_ids", _i_p),
        ("attribute_values", _f_p),
        ("attribute_count", ctypes.c_int),
        ("motion_transforms", _f_p),
        ("motion_step_count", ctypes.c_int),
        ("cryptomatte_object", ctypes.c_uint32),
        ("cryptomatte_asset", ctypes.c_uint32),
        ("holdout", ctypes.c_int),
        ("lightgroup", ctypes.c_int),
        ("shadow_catcher", ctypes.c_int),
        ("shadow_terminator_geometry_offset", ctypes.c_float),
        ("shadow_terminator_shading_offset", ctypes.c_float),
    ]


class LightDesc(ctypes.Structure):
    _c_name_ = "lt_light_desc"
    _fields_ = [
        ("type", ctypes.c_int),
        ("color", ctypes.c_float * 3),
        ("transform", ctypes.c_float * 12),
        ("radius", ctypes.c_float),
        ("spot_size", ctypes.c_float),
        ("spot_blend", ctypes.c_float),
        ("shape", ctypes.c_int),
        ("size_x", ctypes.c_float),
        ("size_y", ctypes.c_float),
        ("angle", ctypes.c_float),
        ("visibility", ctypes.c_uint),
        ("lightgroup", ctypes.c_int),
        ("spread", ctypes.c_float),
    ]


class CameraDesc(ctypes.Structure):
    _c_name_ = "lt_camera_desc"
    _fields_ = [
        ("type", ctypes.c_int),
        ("transform", ctypes.c_float * 12),
        ("focal_length", ctypes.c_float),
        ("sensor_width", ctypes.c_float),
        ("sensor_height", ctypes.c_float),
        ("sensor_fit", ctypes.c_int),
        ("ortho_scale", ctypes.c_float),
        ("shift_x", ctypes.c_float),
        ("shift_y", ctypes.c_float),
        ("clip_start", ctypes.c_float),
        ("clip_end", ctypes.c_float),
        ("pixel_aspect", ctypes.c_float),
        ("use_dof", ctypes.c_int),
        ("focus_distance", ctypes.c_float),
        ("aperture_fstop", ctypes.c_float),
        ("aperture_blades", ctypes.c_int),
        ("aperture_rotation", ctypes.c_float),
        ("aperture_ratio", ctypes.c_float),
        ("panorama_type", ctypes.c_int),
        ("fisheye_fov", ctypes.c_float),
        ("fisheye_lens", ctypes.c_float),
        ("latitude_min", ctypes.c_float),
        ("latitude_max", ctypes.c_float),
        ("longitude_min", ctypes.c_float),
        ("longitude_max", ctypes.c_float),
        ("motion_transforms", _f_p),
        ("motion_step_count", ctypes.c_int),
        ("fisheye_polynomial", ctypes.c_float * 5),
        ("panorama_viewplane", ctypes.c_float * 4),
        ("panorama_frame_aspect", ctypes.c_float),
        ("zoom_pre", ctypes.c_float),
        ("zoom_post", ctypes.c_float),
    ]


class WorldDesc(ctypes.Structure):
    _c_name_ = "lt_world_desc"
    _fields_ = [
        ("color", ctypes.c_float * 3),
        ("strength", ctypes.c_float),
        ("image", ctypes.c_int),
        ("rotation_z", ctypes.c_float),
        ("visibility", ctypes.c_uint),
    ]


class RenderSettings(ctypes.Structure):
    _c_name_ = "lt_render_settings"
    _fields_ = [
        ("width", ctypes.c_int),
        ("height", ctypes.c_int),
        ("border", ctypes.c_int * 4),
        ("samples", ctypes.c_int),
        ("seed", ctypes.c_uint),
        ("sample_offset", ctypes.c_int),
        ("integrator", ctypes.c_int),
        ("max_bounces", ctypes.c_int),
        ("diffuse_bounces", ctypes.c_int),
        ("glossy_bounces", ctypes.c_int),
        ("transmission_bounces", ctypes.c_int),
        ("transparent_bounces", ctypes.c_int),
        ("clamp_direct", ctypes.c_float),
        ("clamp_indirect", ctypes.c_float),
        ("threads", ctypes.c_int),
        ("filter", ctypes.c_int),
        ("filter_width", ctypes.c_float),
        ("transparent_background", ctypes.c_int),
        ("max_camera_length", ctypes.c_int),
        ("max_light_length", ctypes.c_int),
        ("mis_heuristic", ctypes.c_int),
        ("strategy_view_depth", ctypes.c_int),
        ("volume_bounces", ctypes.c_int),
        ("volume_estimator", ctypes.c_int),
        ("volume_step", ctypes.c_float),
        ("time_limit", ctypes.c_float),
        ("noise_target", ctypes.c_float),
        ("adaptive", ctypes.c_int),
        ("min_samples", ctypes.c_int),
        ("passes", ctypes.c_uint),
        ("caller_bytes", ctypes.c_ulonglong),
        ("sample_pattern", ctypes.c_int),
        ("denoise", ctypes.c_int),
        ("mist_start", ctypes.c_float),
        ("mist_depth", ctypes.c_float),
        ("mist_falloff", ctypes.c_float),
        ("cryptomatte", ctypes.c_uint),
        ("cryptomatte_levels", ctypes.c_int),
        ("lightgroup_count", ctypes.c_int),
        ("lightgroup_names", ctypes.POINTER(ctypes.c_char_p)),
        ("aov_count", ctypes.c_int),
        ("aov_names", ctypes.POINTER(ctypes.c_char_p)),
        ("aov_colors", _i_p),
        ("pass_alpha_threshold", ctypes.c_float),
        ("ao_distance", ctypes.c_float),
        ("motion_pass", ctypes.c_int),
        ("shadow_catcher_approximate", ctypes.c_int),
        ("denoise_start_sample", ctypes.c_int),
    ]


# VolumeDesc's grid names (Volume objects: float grids of the file feeding the parameters).
_GRID_FIELDS = ("emission_strength_grid", "blackbody_intensity_grid", "temperature_grid", "temperature_attribute")


class VolumeDesc(ctypes.Structure):
    _c_name_ = "lt_volume_desc"
    _fields_ = [
        ("node", ctypes.c_int),
        ("color", ctypes.c_float * 3),
        ("density", ctypes.c_float),
        ("absorption_color", ctypes.c_float * 3),
        ("anisotropy", ctypes.c_float),
        ("emission_strength", ctypes.c_float),
        ("emission_color", ctypes.c_float * 3),
        ("blackbody_intensity", ctypes.c_float),
        ("blackbody_tint", ctypes.c_float * 3),
        ("temperature", ctypes.c_float),
        ("emission_strength_grid", ctypes.c_char_p),
        ("blackbody_intensity_grid", ctypes.c_char_p),
        ("temperature_grid", ctypes.c_char_p),
        ("temperature_attribute", ctypes.c_char_p),
    ]


class RenderStatus(ctypes.Structure):
    _c_name_ = "lt_render_status"
    _fields_ = [
        ("state", ctypes.c_int),
        ("samples_done", ctypes.c_int),
        ("samples_total", ctypes.c_int),
        ("elapsed_seconds", ctypes.c_double),
        ("remaining_seconds", ctypes.c_double),
        ("nan_samples", ctypes.c_uint64),
        ("rays", ctypes.c_uint64),
        ("rel_error", ctypes.c_double),
        ("halt_reason", ctypes.c_int),
        ("active_pixels", ctypes.c_uint64),
        ("unestimated_pixels", ctypes.c_uint64),
        ("denoised", ctypes.c_int),
        ("denoise_seconds", ctypes.c_double),
    ]


class SceneStats(ctypes.Structure):
    _c_name_ = "lt_scene_stats"
    _fields_ = [
        ("mesh_bvh_builds", ctypes.c_uint64),
        ("top_bvh_builds", ctypes.c_uint64),
        ("light_sampler_builds", ctypes.c_uint64),
        ("emissive_triangles", ctypes.c_uint64),
        ("emissive_instances", ctypes.c_uint64),
        ("image_bytes", ctypes.c_uint64),
        ("image_texels", ctypes.c_uint64),
        ("byte_images", ctypes.c_uint64),
        ("world_map_width", ctypes.c_uint64),
        ("world_map_height", ctypes.c_uint64),
        ("motion_instances", ctypes.c_uint64),
        ("motion_meshes", ctypes.c_uint64),
        ("camera_motion_steps", ctypes.c_uint64),
        ("moving_volumes", ctypes.c_uint64),
    ]


class AbiEntry(ctypes.Structure):
    _c_name_ = "lt_abi_entry"
    _fields_ = [
        ("type", ctypes.c_char_p),
        ("field", ctypes.c_char_p),
        ("value", ctypes.c_longlong),
        ("size", ctypes.c_longlong),
    ]


STRUCTS = (AbiEntry, ImageDesc, ImageFileDesc, ShaderProgram, MeshAttribute, MeshDesc, CurvesAttribute, CurvesDesc,
           InstanceDesc, LightDesc, CameraDesc, WorldDesc, VolumeDesc, SceneStats, RenderSettings, RenderStatus)


# ---- library loading -----------------------------------------------------------------------------

_lib = None
_lib_lock = threading.Lock()


def library_path():
    path = os.environ.get("LANTERN_LIBRARY")
    if path:
        return path
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "liblantern.so")


def _declare(lib, layout=True):
    c_int, c_char_p, c_void_p = ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p
    P = ctypes.POINTER
    scene_p = c_void_p  # opaque lt_scene*
    render_p = c_void_p  # opaque lt_render*
    sig = {
        "lt_abi_version": ([], c_int),
        "lt_version": ([], c_char_p),
        "lt_last_error": ([], c_char_p),
        "lt_abi_layout": ([P(c_int)], P(AbiEntry)),
        "lt_scene_create": ([P(scene_p)], c_int),
        "lt_scene_destroy": ([scene_p], None),
        "lt_scene_warning_count": ([scene_p], c_int),
        "lt_scene_warning": ([scene_p, c_int], c_char_p),
        "lt_scene_add_image": ([scene_p, P(ImageDesc), P(c_int)], c_int),
        "lt_scene_begin_image": ([scene_p, P(ImageDesc), P(P(ctypes.c_float))], c_int),
        "lt_scene_add_image_file": ([scene_p, P(ImageFileDesc), P(c_int)], c_int),
        "lt_scene_end_image": ([scene_p, P(c_int)], c_int),
        "lt_scene_add_material": ([scene_p, P(ShaderProgram), P(c_int)], c_int),
        "lt_scene_set_material_pass_index": ([scene_p, c_int, c_int], c_int),
        "lt_cryptomatte_hash": ([c_char_p, ctypes.c_size_t], ctypes.c_uint32),
        "lt_scene_set_material_cryptomatte": ([scene_p, c_int, ctypes.c_uint32], c_int),
        "lt_scene_add_mesh": ([scene_p, P(MeshDesc), P(c_int)], c_int),
        "lt_scene_add_curves": ([scene_p, P(CurvesDesc), P(c_int)], c_int),
        "lt_scene_add_instance": ([scene_p, P(InstanceDesc), P(c_int)], c_int),
        "lt_scene_add_light": ([scene_p, P(LightDesc)], c_int),
        "lt_scene_set_camera": ([scene_p, P(CameraDesc)], c_int),
        "lt_scene_set_world": ([scene_p, P(WorldDesc)], c_int),
        "lt_scene_set_world_program": ([scene_p, P(ShaderProgram), c_int, ctypes.c_uint], c_int),
        "lt_scene_set_world_lightgroup": ([scene_p, c_int], c_int),
        "lt_scene_set_material_volume": ([scene_p, c_int, P(VolumeDesc), c_int, c_int], c_int),
        "lt_scene_set_world_volume": ([scene_p, P(VolumeDesc), c_int], c_int),
        "lt_scene_set_volume_grid_lightgroup": ([scene_p, c_int, c_int], c_int),
        "lt_scene_set_volume_grid_motion": ([scene_p, c_int, _f_p, c_int], c_int),
        "lt_scene_add_volume_grid": ([scene_p, c_char_p, c_char_p, ctypes.c_float * 12, ctypes.c_float,
                                      ctypes.c_float, ctypes.c_float, P(VolumeDesc), c_int, P(c_int)], c_int),
        "lt_scene_commit": ([scene_p], c_int),
        "lt_scene_set_instance_transform": ([scene_p, c_int, ctypes.c_float * 12], c_int),
        "lt_scene_set_instance_motion": ([scene_p, c_int, _f_p, c_int], c_int),
        "lt_scene_set_instance_values": ([scene_p, c_int, ctypes.c_uint, ctypes.c_float * 4, c_int, P(c_int),
                                          P(ctypes.c_float), c_int], c_int),
        "lt_scene_set_material": ([scene_p, c_int, P(ShaderProgram)], c_int),
        "lt_scene_set_material_displacement": ([scene_p, c_int, P(ShaderProgram), c_int], c_int),
        "lt_scene_clear_lights": ([scene_p], c_int),
        "lt_scene_get_stats": ([scene_p, P(SceneStats)], c_int),
        "lt_render_settings_default": ([P(RenderSettings)], None),
        "lt_render_start": ([scene_p, P(RenderSettings), P(render_p)], c_int),
        "lt_render_poll": ([render_p, P(RenderStatus)], c_int),
        "lt_render_cancel": ([render_p], c_int),
        "lt_render_wait": ([render_p], c_int),
        "lt_pass_channels": ([c_int], c_int),
        "lt_render_read_pass": ([render_p, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_pass_rows": ([render_p, c_int, c_int, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_cryptomatte_rows": ([render_p, c_int, c_int, c_int, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_strategy_grid_rows": ([render_p, c_int, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_lightgroup_rows": ([render_p, c_int, c_int, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_aov_rows": ([render_p, c_int, c_int, c_int, _f_p, ctypes.c_size_t], c_int),
        "lt_render_read_strategy_grid": ([render_p, _f_p, ctypes.c_size_t, ctypes.POINTER(c_int),
                                          ctypes.POINTER(c_int)], c_int),
        "lt_render_destroy": ([render_p], None),
        "lt_render_write_exr": ([render_p, c_char_p], c_int),
        "lt_render_write_exr_attributes": ([render_p, c_char_p, P(c_char_p)], c_int),
        "lt_merge_exr": ([c_char_p, P(c_char_p), c_int], c_int),
    }
    if not layout:
        del sig["lt_abi_layout"]
    for name, (argtypes, restype) in sig.items():
        try:
            fn = getattr(lib, name)
        except AttributeError:
            raise LanternError("Lantern library %s lacks %s: it does not match this add-on"
                               % (lib._name, name)) from None
        fn.argtypes = argtypes
        fn.restype = restype


_enums = {}  # C enum name -> [(constant name without its prefix, value)], from lt_abi_layout


def check_layout(entries, path, structs=STRUCTS, constants=None):
    """Compares this module's declarations with a library's lt_abi_layout table (a list of
    (type, field, value, size)); raises LanternError listing every difference. constants: the
    {NAME: value} declared here for lantern.h's LT_NAME (default: this module's)."""
    if constants is None:
        constants = {k: v for k, v in globals().items()
                     if k.isupper() and type(v) is int and k not in ("ABI_VERSION", "LIGHTGROUP_PASS", "AOV_PASS")}
    sizes, fields, values = {}, {}, {}
    for t, f, value, size in entries:
        if f is None:
            sizes[t] = value
        elif f.startswith("LT_"):
            values[f[3:]] = value
        else:
            fields.setdefault(t, []).append((f, value, size))
    problems = []
    for cls in structs:
        c = cls._c_name_
        if c not in sizes:
            problems.append("%s is not in the library" % c)
            continue
        if ctypes.sizeof(cls) != sizes[c]:
            problems.append("sizeof(%s) is %d in the library, %d here" % (c, sizes[c], ctypes.sizeof(cls)))
        ours = [(f, getattr(cls, f).offset, getattr(cls, f).size) for f, _ in cls._fields_]
        theirs = fields.get(c, [])
        if [f for f, _, _ in ours] != [f for f, _, _ in theirs]:
            problems.append("%s's fields are %s in the library, %s here"
                            % (c, ", ".join(f for f, _, _ in theirs), ", ".join(f for f, _, _ in ours)))
        for (f, off, size), (_, toff, tsize) in zip(ours, theirs):
            if (off, size) != (toff, tsize):
                problems.append("%s.%s has offset %d and size %d in the library, %d and %d here"
                                % (c, f, toff, tsize, off, size))
    for name, value in sorted(constants.items()):
        if name not in values:
            problems.append("LT_%s is not in the library" % name)
        elif values[name] != value:
            problems.append("LT_%s is %d in the library, %d here" % (name, values[name], value))
    if problems:
        raise LanternError("Lantern library %s does not match this add-on's declarations of lantern.h "
                           "(rebuild the library and the add-on from the same checkout): %s"
                           % (path, "; ".join(problems)))


def _layout(loaded):
    n = ctypes.c_int(0)
    table = loaded.lt_abi_layout(ctypes.byref(n))
    return [(e.type.decode(), None if e.field is None else e.field.decode(), e.value, e.size)
            for e in table[:n.value]]


def _enum_table(entries):
    """{C enum: [(name, value)]} with each constant's common prefix removed (LT_INTEGRATOR_PATH:
    PATH), *_COUNT sentinels left out."""
    out = {}
    for t, f, value, size in entries:
        if f is not None and f.startswith("LT_"):
            out.setdefault(t, []).append((f, value))
    for t, consts in out.items():
        names = [f for f, _ in consts]
        prefix = os.path.commonprefix(names) if len(names) > 1 else names[0].rsplit("_", 1)[0] + "_"
        prefix = prefix[:prefix.rfind("_") + 1]
        out[t] = [(f[len(prefix):], v) for f, v in consts if f[len(prefix):] != "COUNT"]
    return out


def enum_names(enum):
    """The constants of a lantern.h enum without their prefix, in declaration order:
    enum_names("lt_integrator") == ["PATH", "BIDIRECTIONAL", "VOLPATH", "VOLUME_DEBUG"]."""
    lib()
    return [name for name, _ in _enums[enum]]


def enum_value(enum, name):
    """enum_value("lt_integrator", "VOLPATH") == LT_INTEGRATOR_VOLPATH, from the library."""
    lib()
    for n, v in _enums[enum]:
        if n == name:
            return v
    raise LanternError("%s has no constant %r (valid: %s)" % (enum, name, ", ".join(enum_names(enum))))


def enum_name(enum, value):
    """The name of value `value` of a lantern.h enum ("?" for none)."""
    lib()
    return next((n for n, v in _enums[enum] if v == value), "?")


# A benchmark against a library from before lt_abi_layout (ABI < 6) turns the check off.
CHECK_LAYOUT = True


def lib():
    """The loaded library (loaded on first use so that the add-on registers without it)."""
    global _lib
    with _lib_lock:
        if _lib is None:
            path = library_path()
            if not os.path.isfile(path):
                raise LanternError(
                    "Lantern's native library was not found at %s. Build it (cmake target "
                    "lantern_shared) and copy liblantern.so next to the add-on, or point the "
                    "LANTERN_LIBRARY environment variable at it." % path)
            try:
                loaded = ctypes.CDLL(path)
            except OSError as e:
                raise LanternError("Could not load Lantern's native library %s: %s" % (path, e)) from e
            loaded.lt_abi_version.restype = ctypes.c_int
            version = loaded.lt_abi_version()
            if version != ABI_VERSION:
                raise LanternError("Lantern library %s has ABI version %d, this add-on needs %d"
                                   % (path, version, ABI_VERSION))
            _declare(loaded, CHECK_LAYOUT)
            if CHECK_LAYOUT:
                entries = _layout(loaded)
                check_layout(entries, path)
                _enums.update(_enum_table(entries))
            _lib = loaded
        return _lib


def version():
    return lib().lt_version().decode("utf-8", "replace")


def _check(status, what):
    if status != OK:
        msg = lib().lt_last_error()
        msg = msg.decode("utf-8", "replace") if msg else ""
        kind = _STATUS_NAMES.get(status, "status %d" % status)
        raise LanternError("%s failed (%s): %s" % (what, kind, msg or "no message"), status, msg)


# Light group g's pass reads as pass id LIGHTGROUP_PASS + g (Render.read_pass_rows): RGB; shader
# AOV i as AOV_PASS + 2 i + (1 for a colour): RGBA or one value. The add-on's own numbers, not
# lantern.h's constants (check_layout leaves them out).
LIGHTGROUP_PASS = 1 << 16
AOV_PASS = 1 << 20


def aov_pass(index, colour):
    return AOV_PASS + 2 * index + int(bool(colour))


def pass_channels(pass_id):
    if pass_id >= AOV_PASS:
        return 4 if pass_id & 1 else 1
    if pass_id >= LIGHTGROUP_PASS:
        return 3
    n = lib().lt_pass_channels(int(pass_id))
    if n <= 0:
        raise LanternError("unknown pass %r" % (pass_id,))
    return n


def cryptomatte_hash(name):
    """MurmurHash3_x86_32 (seed 0) of a name's UTF-8 bytes: its Cryptomatte hash (lantern.h)."""
    b = name.encode("utf-8")
    return int(lib().lt_cryptomatte_hash(b, len(b)))


# ---- numpy helpers ------------------------------------------------------------------------------

def _f32(a, what, size_multiple=1):
    a = np.ascontiguousarray(a, dtype=np.float32).reshape(-1)
    if a.size % size_multiple:
        raise ValueError("%s: %d floats is not a multiple of %d" % (what, a.size, size_multiple))
    return a


def _i32(a, what):
    return np.ascontiguousarray(a, dtype=np.int32).reshape(-1)


def _object_attributes(attributes):
    """(ids, 4 floats each) of [(id, up to 4 values)], or (None, None) for none."""
    if not attributes:
        return None, None
    return (_i32([int(i) for i, _ in attributes], "attribute ids"),
            _f32([float(x) for _, v in attributes for x in (tuple(v) + (0.0,) * 4)[:4]], "attribute values"))


def _fptr(a):
    return None if a is None else a.ctypes.data_as(_f_p)


def _iptr(a):
    return None if a is None else a.ctypes.data_as(_i_p)


def _transform(m):
    """A 3x4 row-major transform from a 4x4 or 3x4 matrix-like (mathutils.Matrix or array)."""
    a = np.asarray(m, dtype=np.float32)
    if a.shape == (4, 4):
        a = a[:3]
    if a.shape != (3, 4):
        raise ValueError("transform must be 3x4 or 4x4, got %s" % (a.shape,))
    return (ctypes.c_float * 12)(*a.reshape(-1).tolist())


def _motion_array(motion):
    """A sequence of transforms (3x4 or 4x4 each) as the core's (steps, 3, 4) float32 array; None
    for None or empty (no motion)."""
    if motion is None or len(motion) == 0:
        return None
    a = np.asarray(motion, dtype=np.float32)
    if a.ndim != 3 or a.shape[1:] not in ((4, 4), (3, 4)):
        raise ValueError("motion: expected transforms of 3x4 or 4x4, got %s" % (a.shape,))
    return np.ascontiguousarray(a[:, :3, :4])


def _motion(desc, motion):
    """Sets desc's motion_transforms and motion_step_count from _motion_array(motion); returns the
    array the pointer refers to."""
    a = _motion_array(motion)
    if a is not None:
        desc.motion_transforms, desc.motion_step_count = _fptr(a), a.shape[0]
    return a


# ---- scene --------------------------------------------------------------------------------------

class Scene:
    """An lt_scene: fill it, commit it, then render it (it must outlive its renders)."""

    def __init__(self):
        self._lib = lib()
        h = ctypes.c_void_p()
        _check(self._lib.lt_scene_create(ctypes.byref(h)), "lt_scene_create")
        self._h = h
        self._renders = []

    @property
    def handle(self):
        if self._h is None:
            raise LanternError("scene is closed")
        return self._h

    def add_image(self, pixels, width, height, channels, srgb=False,
                  interpolation=INTERP_LINEAR, extension=EXTENSION_REPEAT, alpha=ALPHA_IGNORE):
        px = _f32(pixels, "image pixels")
        if px.size != width * height * channels:
            raise ValueError("image: %d floats for %dx%dx%d" % (px.size, width, height, channels))
        d = ImageDesc(int(width), int(height), int(channels), _fptr(px), int(bool(srgb)),
                      int(interpolation), int(extension), int(alpha))
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_image(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_image")
        return out.value

    def add_image_filled(self, fill, width, height, channels, srgb=False,
                         interpolation=INTERP_LINEAR, extension=EXTENSION_REPEAT, alpha=ALPHA_IGNORE,
                         ocio=None):
        """Adds an image whose pixels `fill(array)` writes into the core's own buffer (a float32
        array of width*height*channels): the pixels are copied once. ocio: the (configuration file,
        colour space name) a byte image's values b / 255 are converted from. Returns the image id."""
        config, space = (os.fsencode(ocio[0]), ocio[1].encode()) if ocio else (None, None)
        d = ImageDesc(int(width), int(height), int(channels), None, int(bool(srgb)),
                      int(interpolation), int(extension), int(alpha), config, space)
        ptr = ctypes.POINTER(ctypes.c_float)()
        _check(self._lib.lt_scene_begin_image(self.handle, ctypes.byref(d), ctypes.byref(ptr)),
               "lt_scene_begin_image")
        n = int(width) * int(height) * int(channels)
        # Native float32 ("f"): Blender's foreach_get refuses ctypes' explicit "<f" buffer format.
        fill(np.ctypeslib.as_array(ptr, shape=(n,)).view(np.float32))
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_end_image(self.handle, ctypes.byref(out)), "lt_scene_end_image")
        return out.value

    def add_image_file(self, path, color_space, alpha_mode, use_alpha=False,
                       interpolation=INTERP_LINEAR, extension=EXTENSION_REPEAT, ocio=None):
        """Adds an image the core reads from its file (lt_scene_add_image_file): color_space and
        alpha_mode are lt_color_space / lt_alpha_mode names ("SRGB", "STRAIGHT", ...); ocio: the
        (configuration file, colour space name) an "OTHER" colour space is converted from. Returns
        the image id; raises LanternError (status ERROR_INVALID_ARGUMENT: a file the core leaves to
        Blender, ERROR_IO: unreadable)."""
        config, space = (os.fsencode(ocio[0]), ocio[1].encode()) if ocio else (None, None)
        d = ImageFileDesc(os.fsencode(path), enum_value("lt_color_space", color_space),
                          enum_value("lt_alpha_mode", alpha_mode), int(bool(use_alpha)),
                          int(interpolation), int(extension), config, space)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_image_file(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_image_file")
        return out.value

    def add_material(self, program):
        """program: (code words, constants, registers), as export/nodes compiles a material."""
        d, _keep = _program(program)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_material(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_material")
        return out.value

    def set_material_cryptomatte(self, material, name_hash):
        """The material's Cryptomatte hash (cryptomatte_hash of Material.name)."""
        _check(self._lib.lt_scene_set_material_cryptomatte(self.handle, int(material), int(name_hash) & 0xFFFFFFFF),
               "lt_scene_set_material_cryptomatte")

    def set_material_displacement(self, material, program, method):
        """True displacement (before commit): program (as add_material's) giving the Material
        Output's Displacement, method DISPLACEMENT_TRUE or DISPLACEMENT_BOTH."""
        d, _keep = _program(program)
        _check(self._lib.lt_scene_set_material_displacement(self.handle, int(material), ctypes.byref(d), int(method)),
               "lt_scene_set_material_displacement")

    def set_material_pass_index(self, material, pass_index):
        """Material.pass_index, for the Material Index pass."""
        _check(self._lib.lt_scene_set_material_pass_index(self.handle, int(material), int(pass_index)),
               "lt_scene_set_material_pass_index")

    def add_mesh(self, positions, triangles, corner_normals=None, corner_uvs=None,
                 material_slots=None, texspace_location=(0.0, 0.0, 0.0), texspace_size=(0.0, 0.0, 0.0),
                 attributes=(), motion_positions=None, motion_corner_normals=None, flat_triangles=None):
        """attributes: (id, components, per-corner values) for the mesh's named attributes;
        motion_positions (and motion_corner_normals): a deforming mesh's positions (and corner
        normals) at each motion step, step by step; flat_triangles: with corner_normals, a bool
        per triangle, True for flat-shaded ones."""
        pos = _f32(positions, "positions", 3)
        tri = _i32(triangles, "triangles")
        if tri.size % 3:
            raise ValueError("triangles: %d indices is not a multiple of 3" % tri.size)
        ntri = tri.size // 3
        nrm = None if corner_normals is None else _f32(corner_normals, "corner normals")
        uvs = None if corner_uvs is None else _f32(corner_uvs, "corner uvs")
        mat = None if material_slots is None else _i32(material_slots, "material slots")
        for a, per, what in ((nrm, 9, "corner normals"), (uvs, 6, "corner uvs"),
                             (mat, 1, "material slots")):
            if a is not None and a.size != per * ntri:
                raise ValueError("%s: %d values for %d triangles" % (what, a.size, ntri))
        d = MeshDesc(_fptr(pos), pos.size // 3, _iptr(tri), ntri, _fptr(nrm), _fptr(uvs), _iptr(mat),
                     (ctypes.c_float * 3)(*texspace_location), (ctypes.c_float * 3)(*texspace_size))
        flat = None
        if flat_triangles is not None and nrm is not None:
            flat = np.ascontiguousarray(np.asarray(flat_triangles, dtype=np.uint8).reshape(-1))
            if flat.size != ntri:
                raise ValueError("flat triangles: %d values for %d triangles" % (flat.size, ntri))
            d.flat_triangles = flat.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8))
        attrs = [(int(i), int(n), _f32(v, "attribute %d" % int(i))) for i, n, v in attributes]
        if attrs:
            table = (MeshAttribute * len(attrs))(*[MeshAttribute(i, n, _fptr(v), v.size) for i, n, v in attrs])
            d.attributes = table
            d.attribute_count = len(attrs)
        if motion_positions is not None:
            mpos = _f32(motion_positions, "motion positions")
            steps = mpos.size // max(pos.size, 1)
            if mpos.size != steps * pos.size:
                raise ValueError("motion positions: %d values for %d vertices" % (mpos.size, pos.size // 3))
            d.motion_positions, d.motion_step_count = _fptr(mpos), steps
            if motion_corner_normals is not None and nrm is not None:
                mnrm = _f32(motion_corner_normals, "motion corner normals")
                if mnrm.size != steps * nrm.size:
                    raise ValueError("motion corner normals: %d values for %d steps of %d triangles"
                                     % (mnrm.size, steps, ntri))
                d.motion_corner_normals = _fptr(mnrm)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_mesh(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_mesh")
        return out.value

    def add_curves(self, points, curve_offsets=None, material_slots=None, motion=None, uvs=None, texspace=None,
                   attributes=()):
        """Hair or a point cloud: points (n, 4) of x, y, z, radius (object space); curve_offsets
        (curves + 1, uint32) into them, or None for a point cloud; material_slots per curve;
        motion: the points (steps, n, 4) at the motion steps over the shutter (deformation);
        uvs: the default UV map, (curves, 2), or None; texspace: (location, size) of the texture
        space Generated takes each curve's root through (particle hair's emitter), or None (the
        shading point in object space); attributes: (id, components, per_point,
        values) of the named ones, one value per point or (per_point false) per curve."""
        pts = _f32(points, "curve points", 4)
        mot = None if motion is None else np.ascontiguousarray(motion, dtype=np.float32)
        if mot is not None and (mot.ndim != 3 or mot.shape[1:] != (pts.size // 4, 4)):
            raise ValueError("curve motion points: shape %s for %d points" % (mot.shape, pts.size // 4))
        offs = None
        ncurves = 0
        if curve_offsets is not None:
            offs = np.ascontiguousarray(curve_offsets, dtype=np.uint32)
            ncurves = max(offs.size - 1, 0)
        mat = None if material_slots is None else _i32(material_slots, "curve material slots")
        if mat is not None and mat.size != ncurves:
            raise ValueError("curve material slots: %d values for %d curves" % (mat.size, ncurves))
        d = CurvesDesc(_fptr(pts), pts.size // 4,
                       None if offs is None else offs.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)),
                       ncurves, _iptr(mat), None if mot is None else _fptr(mot),
                       0 if mot is None else mot.shape[0])
        uv = None if uvs is None else _f32(uvs, "curve UVs", 2)
        if uv is not None:
            if uv.size != 2 * ncurves:
                raise ValueError("curve UVs: %d values for %d curves" % (uv.size, ncurves))
            d.curve_uvs = _fptr(uv)
        if texspace is not None:
            d.generated_from_root = 1
            d.texspace_location[:], d.texspace_size[:] = ([float(x) for x in v] for v in texspace)
        attrs = [(int(i), int(n), int(bool(p)), _f32(v, "curve attribute %d" % int(i))) for i, n, p, v in attributes]
        if attrs:
            table = (CurvesAttribute * len(attrs))(*[CurvesAttribute(i, n, p, _fptr(v), v.size)
                                                     for i, n, p, v in attrs])
            d.attributes = table
            d.attribute_count = len(attrs)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_curves(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_curves")
        return out.value

    def add_instance(self, mesh, transform, materials=(), visibility=VISIBLE_ALL, color=(1.0, 1.0, 1.0, 1.0),
                     pass_index=0, random_id=0, attributes=(), motion=None, cryptomatte=(0, 0), holdout=False,
                     lightgroup=0, shadow_catcher=False, terminator=(0.0, 0.0)):
        """color: Object.color; random_id: the uint32 Cycles hashes into Object Info's Random;
        holdout: a holdout object (Object.holdout_get); shadow_catcher: Object.is_shadow_catcher;
        terminator: the shadow terminator's (geometry offset, shading offset), each in [0, 1];
        lightgroup: 0 none, k the light group k - 1;
        attributes: (id, 4 floats) of the object's attributes; motion: the transforms (3x4 or 4x4
        each) at the motion steps over the shutter; cryptomatte: the object's and its asset's
        name hashes (cryptomatte_hash)."""
        mats = _i32(list(materials), "materials") if len(materials) else None
        d = InstanceDesc(int(mesh), _transform(transform), _iptr(mats),
                         0 if mats is None else mats.size, int(visibility))
        d.color[:] = [float(c) for c in (tuple(color) + (1.0,) * 4)[:4]]
        d.pass_index = int(pass_index)
        d.random_id = int(random_id) & 0xFFFFFFFF
        d.cryptomatte_object, d.cryptomatte_asset = (int(h) & 0xFFFFFFFF for h in cryptomatte)
        d.holdout = int(bool(holdout))
        d.lightgroup = int(lightgroup)
        d.shadow_catcher = int(bool(shadow_catcher))
        d.shadow_terminator_geometry_offset, d.shadow_terminator_shading_offset = (float(x) for x in terminator)
        ids, values = _object_attributes(attributes)  # noqa: F841 (kept alive for the call)
        d.attribute_ids, d.attribute_values, d.attribute_count = _iptr(ids), _fptr(values), len(attributes)
        motion_keep = _motion(d, motion)  # noqa: F841 (kept alive for the call)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_instance(self.handle, ctypes.byref(d), ctypes.byref(out)),
               "lt_scene_add_instance")
        return out.value

    def add_light(self, type, color, transform, radius=0.0, spot_size=0.0, spot_blend=0.0,
                  shape=AREA_SQUARE, size_x=0.0, size_y=0.0, angle=0.0, visibility=VISIBLE_ALL, lightgroup=0,
                  spread=math.pi):
        d = LightDesc()
        d.type = int(type)
        d.color[:] = [float(c) for c in color[:3]]
        d.transform = _transform(transform)
        d.radius, d.spot_size, d.spot_blend = radius, spot_size, spot_blend
        d.shape, d.size_x, d.size_y, d.angle = int(shape), size_x, size_y, angle
        d.visibility = int(visibility)
        d.lightgroup = int(lightgroup)
        d.spread = spread
        _check(self._lib.lt_scene_add_light(self.handle, ctypes.byref(d)), "lt_scene_add_light")
        return True

    def set_camera(self, transform, type=CAMERA_PERSPECTIVE, focal_length=50.0,
                   sensor_width=36.0, sensor_height=24.0, sensor_fit=SENSOR_AUTO,
                   ortho_scale=6.0, shift_x=0.0, shift_y=0.0, clip_start=0.1, clip_end=100.0,
                   pixel_aspect=1.0, use_dof=False, focus_distance=10.0, aperture_fstop=2.8,
                   aperture_blades=0, aperture_rotation=0.0, aperture_ratio=1.0,
                   panorama_type=PANORAMA_FISHEYE_EQUISOLID, fisheye_fov=3.14159265,
                   fisheye_lens=10.5, latitude_min=-1.57079633, latitude_max=1.57079633,
                   longitude_min=-3.14159265, longitude_max=3.14159265, motion=None,
                   fisheye_polynomial=FISHEYE_POLYNOMIAL_DEFAULT, panorama_viewplane=(0.0, 0.0, 0.0, 0.0),
                   panorama_frame_aspect=0.0, zoom=None):
        """motion: the camera's transforms at its motion steps over the shutter; zoom: a
        perspective camera's (zoom_pre, zoom_post) over it (lantern.h), or None.
        fisheye_polynomial: the lens polynomial's k0 .. k4 (Cycles' camera settings).
        panorama_viewplane, panorama_frame_aspect: a viewport through a panoramic camera (lantern.h)."""
        d = CameraDesc()
        d.type = int(type)
        d.transform = _transform(transform)
        d.focal_length, d.sensor_width, d.sensor_height = focal_length, sensor_width, sensor_height
        d.sensor_fit, d.ortho_scale = int(sensor_fit), ortho_scale
        d.shift_x, d.shift_y, d.clip_start, d.clip_end = shift_x, shift_y, clip_start, clip_end
        d.pixel_aspect = pixel_aspect
        d.use_dof, d.focus_distance, d.aperture_fstop = int(bool(use_dof)), focus_distance, aperture_fstop
        d.aperture_blades, d.aperture_rotation = int(aperture_blades), aperture_rotation
        d.aperture_ratio, d.panorama_type = aperture_ratio, int(panorama_type)
        d.fisheye_fov, d.fisheye_lens = fisheye_fov, fisheye_lens
        d.latitude_min, d.latitude_max = latitude_min, latitude_max
        d.longitude_min, d.longitude_max = longitude_min, longitude_max
        d.fisheye_polynomial[:] = [float(k) for k in fisheye_polynomial]
        d.panorama_viewplane[:] = [float(v) for v in panorama_viewplane]
        d.panorama_frame_aspect = panorama_frame_aspect
        d.zoom_pre, d.zoom_post = zoom if zoom is not None else (1.0, 1.0)
        motion_keep = _motion(d, motion)  # noqa: F841 (kept alive for the call)
        _check(self._lib.lt_scene_set_camera(self.handle, ctypes.byref(d)), "lt_scene_set_camera")

    def set_world(self, color=(0.0, 0.0, 0.0), strength=1.0, image=-1, rotation_z=0.0,
                  visibility=1):
        d = WorldDesc()
        d.color[:] = [float(c) for c in color[:3]]
        d.strength, d.image, d.rotation_z, d.visibility = strength, int(image), rotation_z, int(visibility)
        _check(self._lib.lt_scene_set_world(self.handle, ctypes.byref(d)), "lt_scene_set_world")

    def set_world_program(self, program, map_resolution=0, visibility=1):
        """The World's Surface as a shader program (as add_material's); map_resolution: the width
        of its importance map (0: automatic)."""
        d, _keep = _program(program)
        _check(self._lib.lt_scene_set_world_program(self.handle, ctypes.byref(d), int(map_resolution),
                                                    int(visibility)), "lt_scene_set_world_program")

    def set_world_lightgroup(self, lightgroup):
        """0: none; k: light group k - 1."""
        _check(self._lib.lt_scene_set_world_lightgroup(self.handle, int(lightgroup)), "lt_scene_set_world_lightgroup")

    @staticmethod
    def _volume_descs(components):
        """A volume's components (one keyword dict, or a list of them; keywords as VolumeDesc's
        fields: node, color, density, absorption_color, anisotropy, emission_strength,
        emission_color, blackbody_intensity, blackbody_tint, temperature, and for Volume objects the
        grid names emission_strength_grid, blackbody_intensity_grid, temperature_grid,
        temperature_attribute) as a VolumeDesc array."""
        if isinstance(components, dict):
            components = [components]
        components = list(components)
        if not components:
            raise ValueError("a volume needs at least one component")
        arr = (VolumeDesc * len(components))()
        for d, c in zip(arr, components):
            d.node = int(c["node"])
            d.color[:] = [float(v) for v in tuple(c.get("color", (1.0, 1.0, 1.0)))[:3]]
            d.density = float(c.get("density", 1.0))
            d.absorption_color[:] = [float(v) for v in tuple(c.get("absorption_color", (0.0, 0.0, 0.0)))[:3]]
            d.anisotropy = float(c.get("anisotropy", 0.0))
            d.emission_strength = float(c.get("emission_strength", 0.0))
            d.emission_color[:] = [float(v) for v in tuple(c.get("emission_color", (1.0, 1.0, 1.0)))[:3]]
            d.blackbody_intensity = float(c.get("blackbody_intensity", 0.0))
            d.blackbody_tint[:] = [float(v) for v in tuple(c.get("blackbody_tint", (1.0, 1.0, 1.0)))[:3]]
            d.temperature = float(c.get("temperature", 1000.0))
            for f in _GRID_FIELDS:
                setattr(d, f, c[f].encode("utf-8") if c.get(f) else None)
        return arr, len(components)

    def set_material_volume(self, material, components, null_surface=True):
        """A homogeneous medium inside the closed meshes using `material`: the sum of `components`
        (Cycles' formulas; lantern.h)."""
        arr, n = self._volume_descs(components)
        _check(self._lib.lt_scene_set_material_volume(self.handle, int(material), arr, n, int(bool(null_surface))),
               "lt_scene_set_material_volume")

    def set_world_volume(self, components):
        """A homogeneous World volume filling the scene (Cycles' formulas); escaped rays cross it to
        infinity."""
        arr, n = self._volume_descs(components)
        _check(self._lib.lt_scene_set_world_volume(self.handle, arr, n), "lt_scene_set_world_volume")

    def add_volume_grid(self, path, grid, transform, components, step=0.0, clipping=0.001, face_offset=0.0,
                        lightgroup=0, motion=None):
        """A Volume object's .vdb grid (step: ray-marching step in world units, 0 for the voxel
        size; clipping: the Volume's Render > Clipping, and face_offset: Cycles' shift of its volume
        mesh, which shape the region its emission fills; lightgroup: its emission's, 0 none, k the
        light group k - 1; motion: its transforms over the shutter, as an instance's); raises
        LanternError (LT_ERROR_IO) with the core's message."""
        arr, n = self._volume_descs(components)
        out = ctypes.c_int(-1)
        _check(self._lib.lt_scene_add_volume_grid(self.handle, os.fsencode(path), grid.encode("utf-8"),
                                                   _transform(transform), float(step), float(clipping),
                                                   float(face_offset), arr, n,
                                                   ctypes.byref(out)),
               "lt_scene_add_volume_grid")
        if lightgroup:
            _check(self._lib.lt_scene_set_volume_grid_lightgroup(self.handle, out.value, int(lightgroup)),
                   "lt_scene_set_volume_grid_lightgroup")
        a = _motion_array(motion)
        if a is not None:
            _check(self._lib.lt_scene_set_volume_grid_motion(self.handle, out.value, _fptr(a), a.shape[0]),
                   "lt_scene_set_volume_grid_motion")
        return out.value

    def commit(self):
        _check(self._lib.lt_scene_commit(self.handle), "lt_scene_commit")

    # Incremental edits (lantern.h): allowed after commit once the scene's renders are closed;
    # commit() again afterwards rebuilds only what they touched.
    def set_instance_transform(self, instance, transform):
        _check(self._lib.lt_scene_set_instance_transform(self.handle, int(instance), _transform(transform)),
               "lt_scene_set_instance_transform")

    def set_instance_motion(self, instance, motion):
        """An instance's transforms over the shutter, as add_instance's motion (None: still)."""
        a = _motion_array(motion)
        _check(self._lib.lt_scene_set_instance_motion(self.handle, int(instance), _fptr(a),
                                                      0 if a is None else a.shape[0]),
               "lt_scene_set_instance_motion")

    def set_instance_values(self, instance, visibility, color, pass_index, attributes=()):
        """An instance's ray visibility, Object Info colour and pass index and its object
        attributes (as add_instance's): a changed visibility needs a commit."""
        ids, values = _object_attributes(attributes)
        rgba = (ctypes.c_float * 4)(*[float(c) for c in (tuple(color) + (1.0,) * 4)[:4]])
        _check(self._lib.lt_scene_set_instance_values(self.handle, int(instance), int(visibility), rgba,
                                                      int(pass_index), _iptr(ids), _fptr(values), len(attributes)),
               "lt_scene_set_instance_values")

    def set_material(self, material, program):
        d, _keep = _program(program)
        _check(self._lib.lt_scene_set_material(self.handle, int(material), ctypes.byref(d)),
               "lt_scene_set_material")

    def clear_lights(self):
        _check(self._lib.lt_scene_clear_lights(self.handle), "lt_scene_clear_lights")

    def stats(self):
        """How often commits built mesh BVHs, the top-level BVH and the light sampler, and the
        emissive triangles and instances the last commit found."""
        st = SceneStats()
        _check(self._lib.lt_scene_get_stats(self.handle, ctypes.byref(st)), "lt_scene_get_stats")
        return {k: getattr(st, k) for k, _ in SceneStats._fields_}

    def warnings(self):
        h = self.handle
        out = []
        for i in range(self._lib.lt_scene_warning_count(h)):
            w = self._lib.lt_scene_warning(h, i)
            if w:
                out.append(w.decode("utf-8", "replace"))
        return out

    def take_warnings(self):
        """The warnings added since the last take_warnings() (export names what they are about)."""
        out = self.warnings()
        taken = getattr(self, "_warnings_taken", 0)
        self._warnings_taken = len(out)
        return out[taken:]

    def render(self, settings):
        return Render(self, settings)

    def close(self):
        """Destroys the scene; renders still using it are cancelled and destroyed first."""
        for r in self._renders:
            r.close()
        self._renders = []
        if self._h is not None:
            self._lib.lt_scene_destroy(self._h)
            self._h = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


# ---- rendering ----------------------------------------------------------------------------------

def _string_pairs(mapping):
    """A NULL-terminated char*[] of key, value, key, value, ..."""
    items = [os.fsencode(str(x)) for kv in mapping.items() for x in kv]
    return (ctypes.c_char_p * (len(items) + 1))(*items, None)


def merge_exr(out_path, part_paths):
    """lt_merge_exr: the sample-weighted merge of sample-split parts into out_path."""
    paths = [os.fsencode(p) for p in part_paths]
    arr = (ctypes.c_char_p * max(1, len(paths)))(*paths)
    _check(lib().lt_merge_exr(os.fsencode(out_path), arr, len(paths)), "lt_merge_exr")


def default_settings():
    s = RenderSettings()
    lib().lt_render_settings_default(ctypes.byref(s))
    return s


class Render:
    """An lt_render. `settings` is a RenderSettings or a dict of its fields (over the defaults)."""

    def __init__(self, scene, settings):
        self._lib = lib()
        self.scene = scene  # keeps the scene alive while the render runs
        if isinstance(settings, dict):
            s = default_settings()
            for k, v in settings.items():
                if k == "border":
                    s.border[:] = [int(x) for x in v]
                elif k == "lightgroups":  # the light groups' names
                    self._lightgroup_names = (ctypes.c_char_p * max(1, len(v)))(*[n.encode("utf-8") for n in v])
                    s.lightgroup_count, s.lightgroup_names = len(v), self._lightgroup_names
                elif k == "aovs":  # [(name, is colour)] of the shader AOVs
                    self._aov_names = (ctypes.c_char_p * max(1, len(v)))(*[n.encode("utf-8") for n, _ in v])
                    self._aov_colors = np.array([int(bool(c)) for _, c in v] or [0], dtype=np.int32)
                    s.aov_count, s.aov_names, s.aov_colors = len(v), self._aov_names, _iptr(self._aov_colors)
                else:
                    setattr(s, k, v)
            settings = s
        self.settings = settings
        self._h = None

    @property
    def handle(self):
        if self._h is None:
            raise LanternError("render is not running (call start) or is closed")
        return self._h

    @property
    def region_size(self):
        """(width, height) of the rendered region: the border if one is set, else the frame."""
        b = list(self.settings.border)
        if any(b):
            return b[1] - b[0], b[3] - b[2]
        return self.settings.width, self.settings.height

    def start(self):
        h = ctypes.c_void_p()
        _check(self._lib.lt_render_start(self.scene.handle, ctypes.byref(self.settings),
                                         ctypes.byref(h)), "lt_render_start")
        self._h = h
        self.scene._renders.append(self)
        return self

    def poll(self):
        st = RenderStatus()
        _check(self._lib.lt_render_poll(self.handle, ctypes.byref(st)), "lt_render_poll")
        return st

    def cancel(self):
        _check(self._lib.lt_render_cancel(self.handle), "lt_render_cancel")

    def wait(self):
        _check(self._lib.lt_render_wait(self.handle), "lt_render_wait")

    def pass_size(self, pass_id):
        w, h = self.region_size
        return w * h * pass_channels(pass_id)

    def read_pass(self, pass_id, out=None):
        """Fills `out` (float32 contiguous, width*height*channels of the region) and returns it."""
        n = self.pass_size(pass_id)
        if out is None:
            out = np.empty(n, dtype=np.float32)
        if out.dtype != np.float32 or not out.flags["C_CONTIGUOUS"] or out.size != n:
            raise ValueError("read_pass needs a contiguous float32 array of %d floats" % n)
        _check(self._lib.lt_render_read_pass(self.handle, int(pass_id), _fptr(out), out.size),
               "lt_render_read_pass")
        return out

    def read_pass_rows(self, pass_id, y0, rows, out):
        """Fills `out` (float32 contiguous, width*rows*channels) with rows [y0, y0 + rows) of the
        region (row 0 at the bottom) and returns it."""
        n = self.region_size[0] * rows * pass_channels(pass_id)
        if out.dtype != np.float32 or not out.flags["C_CONTIGUOUS"] or out.size != n:
            raise ValueError("read_pass_rows needs a contiguous float32 array of %d floats" % n)
        if pass_id >= AOV_PASS:
            _check(self._lib.lt_render_read_aov_rows(self.handle, int((pass_id - AOV_PASS) >> 1), int(y0), int(rows),
                                                     _fptr(out), out.size), "lt_render_read_aov_rows")
            return out
        if pass_id >= LIGHTGROUP_PASS:
            _check(self._lib.lt_render_read_lightgroup_rows(self.handle, int(pass_id - LIGHTGROUP_PASS), int(y0),
                                                            int(rows), _fptr(out), out.size),
                   "lt_render_read_lightgroup_rows")
            return out
        _check(self._lib.lt_render_read_pass_rows(self.handle, int(pass_id), int(y0), int(rows), _fptr(out),
                                                  out.size), "lt_render_read_pass_rows")
        return out

    def read_cryptomatte_rows(self, type_bit, layer, y0, rows, out):
        """Fills `out` (float32 contiguous, width*rows*4) with rows [y0, y0 + rows) of Cryptomatte
        layer `layer` (CryptoObject00, 01, ...) of the type (CRYPTOMATTE_*) and returns it."""
        n = self.region_size[0] * rows * 4
        if out.dtype != np.float32 or not out.flags["C_CONTIGUOUS"] or out.size != n:
            raise ValueError("read_cryptomatte_rows needs a contiguous float32 array of %d floats" % n)
        _check(self._lib.lt_render_read_cryptomatte_rows(self.handle, int(type_bit), int(layer), int(y0), int(rows),
                                                         _fptr(out), out.size), "lt_render_read_cryptomatte_rows")
        return out

    def strategy_grid_size(self):
        """(width, height) of the BDPT strategy view (read_strategy_grid)."""
        w, h = ctypes.c_int(), ctypes.c_int()
        _check(self._lib.lt_render_read_strategy_grid(self.handle, None, 0, ctypes.byref(w), ctypes.byref(h)),
               "lt_render_read_strategy_grid")
        return w.value, h.value

    def read_strategy_grid(self, band_pixels=1 << 16):
        """The BDPT strategy view of a stopped render: float32 RGBA array (height, width, 4), alpha
        1, rows bottom to top; rows are path depths (0 at the top), columns s = 0, 1, ... Read a
        band of rows at a time, straight into the array the caller keeps."""
        w, h = self.strategy_grid_size()
        rgba = np.ones((h, w, 4), dtype=np.float32)
        rows = max(1, min(h, band_pixels // max(w, 1)))
        band = np.empty(w * rows * 3, dtype=np.float32)
        for y0 in range(0, h, rows):
            n = min(rows, h - y0)
            buf = band[:w * n * 3]
            _check(self._lib.lt_render_read_strategy_grid_rows(self.handle, y0, n, _fptr(buf), buf.size),
                   "lt_render_read_strategy_grid_rows")
            rgba[y0:y0 + n, :, :3] = buf.reshape(n, w, 3)
        return rgba

    def write_exr(self, path, attributes=None):
        """Writes every pass to a 32-bit float EXR; `attributes`: extra header strings (dict)."""
        if not attributes:
            _check(self._lib.lt_render_write_exr(self.handle, os.fsencode(path)), "lt_render_write_exr")
            return
        _check(self._lib.lt_render_write_exr_attributes(self.handle, os.fsencode(path),
                                                        _string_pairs(attributes)),
               "lt_render_write_exr_attributes")

    def close(self):
        if self._h is not None:
            h, self._h = self._h, None
            # Destroying a running render would free what its threads use: stop it first.
            self._lib.lt_render_cancel(h)
            self._lib.lt_render_wait(h)
            self._lib.lt_render_destroy(h)
            try:
                self.scene._renders.remove(self)
            except ValueError:
                pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
