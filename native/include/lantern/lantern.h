/* Lantern's C ABI: the only surface the add-on, the CLI and the tests see.
 *
 * Conventions (see DESIGN.md):
 *  - opaque handles, plain structs, int status codes; lt_last_error() returns the message of the
 *    last failing call on the calling thread;
 *  - every bulk array is copied by the core; the caller keeps ownership;
 *  - transforms are row-major 3x4 (object to world), Blender's world space, metres;
 *  - colours are linear RGB; light "color" is Blender's colour x energy (W, or W/m^2 for sun).
 */
#ifndef LANTERN_H
#define LANTERN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define LT_API __declspec(dllexport)
#else
#define LT_API __attribute__((visibility("default")))
#endif

/* ABI versions: 2: lt_render_settings.sample_offset; 3: halting settings and status; 4: volumes
 * are arrays of components with emission; lt_scene_stats counts emissive triangles;
 * lt_scene_add_volume_grid takes a step; 5: lt_render_settings.passes and caller_bytes;
 * lt_render_wait reports a failed render; lt_scene_begin/end_image; image memory in lt_scene_stats;
 * lt_render_status.unestimated_pixels; 6: lt_abi_layout; default samples 64 (the add-on's);
 * 7: materials are shader programs; meshes carry their texture space and attributes
 * (lt_mesh_attribute), instances their Object Info values and attributes, images their alpha;
 * 8: cubic interpolation; lt_scene_add_image_file (files read by the core); pass and strategy
 * rows read in bands; lt_scene_set_world_program and the world map's size in lt_scene_stats;
 * 9: lt_render_settings.sample_pattern; 10: lt_camera_desc's lens and panorama fields;
 * 11: denoising (lt_render_settings.denoise, lt_render_status.denoised and denoise_seconds, the
 * Noisy Image and Denoising passes); 12: Cycles' light and data passes (LT_PASS_DIFFUSE_DIRECT
 * on), lt_render_settings' mist fields, lt_scene_set_material_pass_index; 13: motion blur (motion
 * steps of lt_mesh_desc, lt_instance_desc and lt_camera_desc; motion counts in lt_scene_stats);
 * 14: curves and points (lt_curves_desc, lt_scene_add_curves); 15: Cryptomatte
 * (lt_cryptomatte_hash, lt_instance_desc's and lt_scene_set_material_cryptomatte's name hashes,
 * lt_render_settings.cryptomatte and cryptomatte_levels, lt_render_read_cryptomatte_rows); 16:
 * lt_instance_desc.holdout; light groups (the lightgroup fields, lt_scene_set_world_lightgroup,
 * lt_render_read_lightgroup_rows); shader AOVs (lt_render_settings.aov_*, pass_alpha_threshold,
 * lt_render_read_aov_rows); 17: the AO and Vector passes (LT_PASS_AO, LT_PASS_VECTOR,
 * lt_render_settings.ao_distance and motion_pass); the Mirror Ball and Fisheye Lens Polynomial
 * panoramas (lt_camera_desc.fisheye_polynomial); panoramas in the viewport (panorama_viewplane,
 * panorama_frame_aspect); the shadow catcher
 * (lt_instance_desc.shadow_catcher, lt_render_settings.shadow_catcher_approximate,
 * LT_PASS_SHADOW_CATCHER); 18: true displacement (lt_scene_set_material_displacement,
 * lt_displacement_method, lt_mesh_desc.flat_triangles; the Bevel node;
 * lt_image_file_desc.ocio_config and ocio_space: OpenColorIO colour spaces;
 * the Equiangular Cubemap Face panorama; lt_instance_desc's shadow terminator offsets;
 * lt_render_settings.denoise_start_sample: the viewport's denoising); 19: emission of Volume
 * objects and World volumes (lt_volume_desc's grid names, lt_scene_set_volume_grid_lightgroup);
 * 20: area lights' spread (lt_light_desc.spread); 21: lt_scene_add_volume_grid's clipping and
 * face_offset (a Volume object's emission confined to Cycles' volume mesh); deforming curves and
 * points (lt_curves_desc.motion_points and motion_step_count); 22: lt_image_desc.ocio_config and
 * ocio_space (byte images Blender loads in other colour spaces); 23: a perspective camera's zoom over
 * the shutter (lt_camera_desc.zoom_pre and zoom_post); 24: attributes, UVs and generated coordinates of
 * curves and points (lt_curves_desc.curve_uvs, generated_from_root, texspace_location and texspace_size, attributes,
 * lt_curves_attribute); 25: lt_scene_set_instance_values; 26: lt_scene_set_volume_grid_motion; 27:
 * lt_scene_stats.moving_volumes, lt_scene_set_instance_motion. */
#define LT_ABI_VERSION 27

enum lt_status {
  LT_OK = 0,
  LT_ERROR_INVALID_ARGUMENT = 1,
  LT_ERROR_OUT_OF_MEMORY = 2,
  LT_ERROR_IO = 3,
  LT_ERROR_STATE = 4,
  LT_ERROR_INTERNAL = 5
};

typedef struct lt_scene lt_scene;
typedef struct lt_render lt_render;

LT_API int lt_abi_version(void);
LT_API const char* lt_version(void);
LT_API const char* lt_last_error(void);

/* The ABI's layout as this library was compiled, for bindings that declare it by hand (the add-on's
 * ctypes, addon/lantern/core.py) to check at load and to take enum names from. One entry per struct
 * (field NULL: value = sizeof), per struct field (value = offsetof, size = its sizeof) and per enum
 * constant (type = the enum's name, field = the constant's name, value = its value, size 0), in
 * declaration order. The table is static; *count is set to its length. */
typedef struct lt_abi_entry {
  const char* type;  /* "lt_render_settings", "lt_integrator", ... */
  const char* field; /* "samples", "LT_INTEGRATOR_PATH", ...; NULL for a struct's own entry */
  long long value;
  long long size;
} lt_abi_entry;
LT_API const lt_abi_entry* lt_abi_layout(int* count);

/* ---- scene ------------------------------------------------------------------------------- */

LT_API int lt_scene_create(lt_scene** out);
LT_API void lt_scene_destroy(lt_scene* scene);

/* Warnings collected while building the scene (degenerate triangles dropped, zero-area light...). */
LT_API int lt_scene_warning_count(const lt_scene* scene);
LT_API const char* lt_scene_warning(const lt_scene* scene, int index);

/* Images (textures, environment maps). pixels: width*height*channels floats, rows bottom to top
 * as Blender stores them. channels 1, 3 or 4. srgb != 0: values are sRGB-encoded and are decoded
 * to linear when loaded. */
/* Cubic: Cycles' CPU bicubic B-spline (Blender's Cubic, and Smart on the CPU). */
enum lt_interpolation { LT_INTERP_LINEAR = 0, LT_INTERP_CLOSEST = 1, LT_INTERP_CUBIC = 2 };
enum lt_extension { LT_EXTENSION_REPEAT = 0, LT_EXTENSION_EXTEND = 1, LT_EXTENSION_CLIP = 2 };
/* What a 4-channel image's alpha means (Cycles' image alpha types): IGNORE drops it (opaque);
 * STRAIGHT colours are premultiplied when stored, as Cycles associates them (bytes: (c a) / 255 in
 * integers); PREMULTIPLIED are kept; CHANNEL_PACKED keeps alpha apart from colours that are never
 * multiplied or divided by it. */
enum lt_image_alpha {
  LT_ALPHA_IGNORE = 0,
  LT_ALPHA_STRAIGHT = 1,
  LT_ALPHA_PREMULTIPLIED = 2,
  LT_ALPHA_CHANNEL_PACKED = 3
};
typedef struct lt_image_desc {
  int width, height, channels;
  const float* pixels;
  int srgb;
  int interpolation; /* lt_interpolation */
  int extension;     /* lt_extension */
  int alpha;         /* lt_image_alpha */
  /* A byte image in another colour space (ABI 22; NULL or "": none): ocio_space of the OpenColorIO
   * configuration file ocio_config, the pixels b / 255 as Blender gives them (srgb must be 0).
   * Converted to scene linear as Cycles 3.4 loads such an image from Blender (colours associated
   * with alpha unless it is IGNORE or CHANNEL_PACKED, half floats through OpenColorIO's processor
   * to the scene_linear role) and held as half floats. Copied: the strings need not outlive the call. */
  const char* ocio_config;
  const char* ocio_space;
} lt_image_desc;
LT_API int lt_scene_add_image(lt_scene* scene, const lt_image_desc* desc, int* out_id);
/* The same without a caller's copy of the pixels: lt_scene_begin_image allocates the image's
 * width*height*channels floats (desc->pixels is ignored) and returns them in *out_pixels for the
 * caller to fill; lt_scene_end_image takes them over and gives the image id. Images are stored at
 * the source's precision: 8 bits per channel when every value is b * (1.0f / 255.0f) for a byte b
 * (what Blender gives for byte images; lossless), else 32-bit float; 1 channel for grey images,
 * else RGB (alpha is not used). Beginning another image drops an unfinished one. */
LT_API int lt_scene_begin_image(lt_scene* scene, const lt_image_desc* desc, float** out_pixels);
LT_API int lt_scene_end_image(lt_scene* scene, int* out_id);
/* An image the core reads from its file itself (OpenImageIO), as Cycles does, so that the caller
 * never loads the pixels: they are held once, at the file's precision (8-bit files as bytes, half
 * OpenEXR files as half floats unless the alpha mode is Straight, others as float), and filtered
 * there with any lt_interpolation.
 * The texels are those Blender 3.4 gives in Image.pixels for an image datablock of this colour
 * space and alpha mode, given to lt_scene_add_image with that datablock's srgb and alpha
 * (native/src/io/image_file.h). PNG (8 and 16 bits), JPEG, TIFF (8, 16, 32 bits), TGA, Radiance HDR
 * and single-part RGB(A) OpenEXR. Refused with
 * LT_ERROR_INVALID_ARGUMENT (and why) for what Blender's loading would change otherwise (a float
 * file in a colour space other than Linear or a data space, variants Blender reads its own way,
 * other formats): the caller then loads it
 * another way. A file that cannot
 * be opened or read: LT_ERROR_IO. Added without an ABI version bump (still 7). */
enum lt_color_space {
  LT_COLOR_SPACE_SRGB = 0,
  LT_COLOR_SPACE_LINEAR = 1, /* scene linear */
  LT_COLOR_SPACE_DATA = 2,   /* Non-Color, Raw (ColorManagedInputColorspaceSettings.is_data) */
  LT_COLOR_SPACE_OTHER = 3   /* another: ocio_space of ocio_config (below) */
};
enum lt_alpha_mode { /* Blender's Image.alpha_mode */
                     LT_ALPHA_MODE_STRAIGHT = 0,
                     LT_ALPHA_MODE_PREMULTIPLIED = 1,
                     LT_ALPHA_MODE_CHANNEL_PACKED = 2,
                     LT_ALPHA_MODE_NONE = 3
};
typedef struct lt_image_file_desc {
  const char* path;
  int color_space;   /* lt_color_space */
  int alpha_mode;    /* lt_alpha_mode */
  int use_alpha;     /* != 0: keep the alpha as Cycles reads it (image textures), else drop it */
  int interpolation; /* lt_interpolation */
  int extension;     /* lt_extension */
  /* LT_COLOR_SPACE_OTHER: the OpenColorIO configuration file and the colour space's name in it.
   * 8-bit RGB(A) and grey files are converted to scene linear as Cycles 3.4 converts them (half
   * floats through OpenColorIO's processor to the scene_linear role) and held as half floats; other
   * files are refused (LT_ERROR_INVALID_ARGUMENT). NULL (ABI 17's callers): 8-bit values are used
   * as they are. */
  const char* ocio_config;
  const char* ocio_space;
} lt_image_file_desc;
LT_API int lt_scene_add_image_file(lt_scene* scene, const lt_image_file_desc* desc, int* out_id);

/* Materials are shader programs: a material's node tree compiled by the add-on
 * (addon/lantern/export/nodes/) for the core's register machine (native/src/shading/program.h
 * documents the encoding and the opcodes). code: instruction words; constants: the constant pool;
 * registers: how many float registers the program writes. Programs are validated (operands in
 * range, registers written before they are read, image ids that exist) and refused otherwise. */
typedef struct lt_shader_program {
  const uint32_t* code;
  int code_words;
  const float* constants;
  int constant_count;
  int registers;
} lt_shader_program;

LT_API int lt_scene_add_material(lt_scene* scene, const lt_shader_program* program, int* out_id);
/* Material.pass_index, for LT_PASS_MATERIAL_INDEX (kept by lt_scene_set_material). */
LT_API int lt_scene_set_material_pass_index(lt_scene* scene, int material, int pass_index);

/* True displacement (Cycles' Material > Settings > Displacement: Displacement Only, Displacement
 * and Bump). `program` gives the Material Output's Displacement through its SetDisplacement
 * instruction (shading/inputs.h), a world-space offset; at the first lt_scene_commit each mesh's
 * vertices move by it, evaluated once per vertex with the mesh's first instance (its transform
 * and material slots) at the vertex's corner of the first triangle (in index order) whose material
 * displaces (Cycles' mesh_displace.cpp). TRUE then recomputes the smooth normals of the triangles
 * of its materials; BOTH keeps the undisplaced smooth normals for the surface program's bump.
 * LT_DISPLACEMENT_BUMP (program NULL) removes it. Before the first commit only. */
enum lt_displacement_method { LT_DISPLACEMENT_BUMP = 0, LT_DISPLACEMENT_TRUE = 1, LT_DISPLACEMENT_BOTH = 2 };
LT_API int lt_scene_set_material_displacement(lt_scene* scene, int material, const lt_shader_program* program,
                                              int method);

/* Cryptomatte (docs/passes.md): MurmurHash3_x86_32 (seed 0) of `length` bytes (a name in UTF-8),
 * the hash the Cryptomatte specification and Cycles give names. The core takes a name's hash and
 * writes the id the specification makes of it (uint32_to_float32). Hash 0 stands for no id. */
LT_API uint32_t lt_cryptomatte_hash(const char* bytes, size_t length);
/* The material's Cryptomatte hash (of Material.name; kept by lt_scene_set_material). */
LT_API int lt_scene_set_material_cryptomatte(lt_scene* scene, int material, uint32_t hash);

/* A named per-corner attribute of a mesh, read by the Attribute, UV Map, Color Attribute, Tangent
 * and Normal Map nodes (kOpAttribute... in native/src/shading/inputs.h): the add-on gives each
 * name a small id per scene (0 <= id < 65536, each id at most once per mesh). components 1 to 4
 * (UV maps 2, colours 4 (linear RGBA), tangents 4: the tangent then its sign); value_count must
 * be components x 3 x triangle_count and every value finite. */
typedef struct lt_mesh_attribute {
  int id;
  int components;
  const float* values;
  int value_count;
} lt_mesh_attribute;

/* A mesh of triangles. corner_normals (9 floats per triangle) and corner_uvs (6 per triangle) may
 * be NULL; material_slots (one per triangle, index into the instance's material list) may be NULL. */
typedef struct lt_mesh_desc {
  const float* positions; /* 3 * vertex_count */
  int vertex_count;
  const int* triangles; /* 3 * triangle_count vertex indices */
  int triangle_count;
  const float* corner_normals;
  const float* corner_uvs;
  const int* material_slots;
  /* Blender's texture space (Mesh.texspace_location, texspace_size), for Generated coordinates;
   * a size of (0, 0, 0) stands for Blender's automatic one: the mesh's bounds. */
  float texspace_location[3];
  float texspace_size[3];
  const lt_mesh_attribute* attributes; /* may be NULL when attribute_count is 0 */
  int attribute_count;
  /* Deformation motion blur: motion_step_count (0: none, else 2 to 129, odd) sets of positions
   * equally spaced over the shutter, 3 * vertex_count finite floats each, the centre one equal to
   * positions; and, when corner_normals is given, as many sets of corner normals (NULL: the
   * centre's at every time). Same triangles at every step. */
  const float* motion_positions;
  const float* motion_corner_normals;
  int motion_step_count;
  /* With corner_normals: one per triangle, nonzero for a flat-shaded triangle (its corner normals
   * are its face normal), which true displacement gives its displaced face normal; NULL: none. */
  const uint8_t* flat_triangles;
} lt_mesh_desc;
LT_API int lt_scene_add_mesh(lt_scene* scene, const lt_mesh_desc* desc, int* out_id);

/* Curves (hair) or a point cloud, object space; the id is a mesh id for lt_scene_add_instance.
 * points: x, y, z, radius per point. curve_offsets: curve_count + 1 ascending indices into the
 * points (curve k has points [offsets[k], offsets[k + 1])); NULL with curve_count 0: a point
 * cloud (spheres). Curves render as Cycles' thick (3D) curves: round Catmull-Rom splines through
 * the points, the radius interpolated the same way. material_slots: one per curve (NULL: slot 0).
 * Curves of fewer than 2 points, of zero length or radius, or with a non-finite point, and points
 * of zero radius or non-finite positions are dropped with a warning; negative radii become 0.
 * Deformation motion blur: motion_step_count (0: none, else 3 to 129, odd) sets of points equally
 * spaced over the shutter, 4 * point_count floats each (x, y, z, radius), the centre one equal to
 * points; the keys move linearly between steps (Embree's vertex motion, as Cycles'). A curve or
 * point non-finite at any step is dropped. */
/* A named attribute of curves or points, read as lt_mesh_attribute's (same ids, 1 to 4 components,
 * finite values): per_point nonzero, one value per point, which a curve segment interpolates
 * linearly between its two keys (Cycles' curve key attributes); 0, one value per curve (Cycles'
 * curve attributes; points take per_point only). */
typedef struct lt_curves_attribute {
  int id;
  int components;
  int per_point;
  const float* values;
  int value_count;
} lt_curves_attribute;

typedef struct lt_curves_desc {
  const float* points;
  uint32_t point_count;
  const uint32_t* curve_offsets;
  uint32_t curve_count;
  const int* material_slots;
  const float* motion_points;
  int motion_step_count;
  /* The default UV map (Texture Coordinate's UV), 2 finite floats per curve (Cycles' hair UV: the
   * emitter's UV at the root of particle hair, a Curves object's surface UV); NULL: (0, 0). */
  const float* curve_uvs;
  /* Texture Coordinate's Generated. generated_from_root nonzero (Cycles' particle hair): each
   * curve's root key through the emitter's texture space, (root - texspace_location) /
   * (2 texspace_size) + 0.5, 0.5 on an axis of size 0. 0, and on points: the shading point in
   * object space (Cycles' fallback where a geometry has no generated coordinates). */
  int generated_from_root;
  float texspace_location[3];
  float texspace_size[3];
  const lt_curves_attribute* attributes; /* may be NULL when attribute_count is 0 */
  int attribute_count;
} lt_curves_desc;
LT_API int lt_scene_add_curves(lt_scene* scene, const lt_curves_desc* desc, int* out_id);

/* Ray visibility flags (Cycles' Object > Visibility > Ray Visibility). */
enum lt_visibility {
  LT_VISIBLE_CAMERA = 1,
  LT_VISIBLE_DIFFUSE = 2,
  LT_VISIBLE_GLOSSY = 4,
  LT_VISIBLE_TRANSMISSION = 8,
  LT_VISIBLE_SHADOW = 16,
  LT_VISIBLE_ALL = 31
};

typedef struct lt_instance_desc {
  int mesh;
  float transform[12];
  const int* materials; /* material id per slot; -1 or slot past the end: default material */
  int material_count;
  unsigned visibility; /* lt_visibility bits */
  /* Object Info: Object.color (RGBA, linear), pass_index, and the random id Cycles hashes into
   * its Random output (random_id / 0xFFFFFFFF): DepsgraphObjectInstance.random_id for instances,
   * hash_uint2(hash_string(name), 0) for objects. A zeroed desc gives colour and alpha 0. */
  float color[4];
  int pass_index;
  uint32_t random_id;
  /* Attributes of the object (Attribute node, Object and Instancer types): attribute_count ids
   * (0 <= id < 65536) and 4 finite floats each. */
  const int* attribute_ids;
  const float* attribute_values;
  int attribute_count;
  /* Transform motion blur: motion_step_count (0: none, else 2 to 129, odd) transforms of 12 floats
   * equally spaced over the shutter, the centre one equal to transform; interpolated as Cycles
   * (translation and scale linearly, rotation by quaternion slerp). Steps that are not finite or
   * not invertible leave the instance without motion (a warning). */
  const float* motion_transforms;
  int motion_step_count;
  /* Cryptomatte: lt_cryptomatte_hash of the object's name and of its asset's (the top-most
   * parent's name); 0: none. */
  uint32_t cryptomatte_object, cryptomatte_asset;
  /* Nonzero: a holdout object (Object.holdout_get: its own flag or a holdout collection's), which
   * camera rays see as Cycles does: transparent film where it covers, its Transparent closures kept. */
  int holdout;
  /* The light group of its emission: 0 none, k > 0 the render's light group k - 1
   * (lt_render_settings.lightgroup_count); the same in lt_light_desc. */
  int lightgroup;
  /* Nonzero: a shadow catcher (Object.is_shadow_catcher, or its instancer's), which PATH and
   * VOLPATH render as Cycles 3.4: Combined becomes the catchers' matte and LT_PASS_SHADOW_CATCHER
   * their shadows (BIDIRECTIONAL renders catchers as ordinary objects). */
  int shadow_catcher;
  /* Cycles' shadow terminator settings (Object.cycles.shadow_terminator_geometry_offset, Blender's
   * default 0.1, and shadow_terminator_offset, default 0), each in [0, 1]; 0 turns either off (a
   * zeroed desc). The geometry offset moves next-event shadow rays from smooth-shaded triangles
   * onto the surface their normals imply; the shading offset remaps the BSDF's light cosine. */
  float shadow_terminator_geometry_offset;
  float shadow_terminator_shading_offset;
} lt_instance_desc;
LT_API int lt_scene_add_instance(lt_scene* scene, const lt_instance_desc* desc, int* out_id);

enum lt_light_type { LT_LIGHT_POINT = 0, LT_LIGHT_SPOT = 1, LT_LIGHT_AREA = 2, LT_LIGHT_SUN = 3 };
enum lt_area_shape { LT_AREA_SQUARE = 0, LT_AREA_RECTANGLE = 1, LT_AREA_DISK = 2, LT_AREA_ELLIPSE = 3 };
typedef struct lt_light_desc {
  int type;
  float color[3]; /* Blender colour x energy */
  float transform[12];
  float radius;     /* point, spot: shadow_soft_size */
  float spot_size;  /* full cone angle, radians */
  float spot_blend; /* 0..1 */
  int shape;        /* lt_area_shape */
  float size_x, size_y;
  float angle; /* sun: angular diameter, radians */
  unsigned visibility;
  int lightgroup; /* 0 none, k > 0 light group k - 1 (lt_instance_desc.lightgroup) */
  /* area: Blender's Spread, radians (Cycles 3.4: at least 1 degree, up to pi); 0 (a zeroed
   * descriptor) and pi: none */
  float spread;
} lt_light_desc;
LT_API int lt_scene_add_light(lt_scene* scene, const lt_light_desc* desc);

enum lt_camera_type { LT_CAMERA_PERSPECTIVE = 0, LT_CAMERA_ORTHOGRAPHIC = 1, LT_CAMERA_PANORAMA = 2 };
enum lt_sensor_fit { LT_SENSOR_AUTO = 0, LT_SENSOR_HORIZONTAL = 1, LT_SENSOR_VERTICAL = 2 };
/* Cycles 3.4's panoramic projections Lantern renders (Blender's cam.cycles.panorama_type). */
enum lt_panorama_type {
  LT_PANORAMA_EQUIRECTANGULAR = 0,
  LT_PANORAMA_FISHEYE_EQUIDISTANT = 1,
  LT_PANORAMA_FISHEYE_EQUISOLID = 2,
  LT_PANORAMA_MIRRORBALL = 3,
  LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL = 4,
  LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE = 5
};
typedef struct lt_camera_desc {
  int type;
  float transform[12];               /* camera looks down local -Z, +Y up */
  float focal_length;                /* mm */
  float sensor_width, sensor_height; /* mm */
  int sensor_fit;
  float ortho_scale;
  float shift_x, shift_y;
  float clip_start, clip_end;
  float pixel_aspect; /* pixel_aspect_y / pixel_aspect_x, 1 for square pixels */
  /* Depth of field (Blender's camera.dof): the core takes Cycles' aperture radius from the
   * F-stop (focal length in metres / (2 F-stop), 1 / (2 F-stop) for orthographic; F-stop clamped
   * to 1e-5). focus_distance: along the view axis (> 0 with use_dof; a focus object's resolved by
   * the caller). Blades < 3 make a round aperture. Panoramas with depth of field and orthographic
   * cameras render it but are not connectable for BIDIRECTIONAL's light tracing (docs). */
  int use_dof;
  float focus_distance;
  float aperture_fstop; /* >= 0 */
  int aperture_blades;  /* 0 .. 16 */
  float aperture_rotation;
  float aperture_ratio; /* > 0 */
  /* LT_CAMERA_PANORAMA (Cycles' camera settings): lt_panorama_type, the fisheyes' field of view
   * (radians, > 0), the equisolid's lens (mm, > 0), the equirectangular's ranges (radians). */
  int panorama_type;
  float fisheye_fov, fisheye_lens;
  float latitude_min, latitude_max, longitude_min, longitude_max;
  /* Camera motion blur: motion_step_count (0: none, else 2 to 129, odd) transforms as
   * lt_instance_desc's, the centre one equal to transform. */
  const float* motion_transforms;
  int motion_step_count;
  /* LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL: Cycles' k0 .. k4 (finite); the angle from the axis at
   * sensor radius r (mm) is -(k0 + k1 r + k2 r^2 + k3 r^3 + k4 r^4), seen within fisheye_fov. */
  float fisheye_polynomial[5];
  /* LT_CAMERA_PANORAMA seen by a viewport through the camera (Cycles' pano_viewplane): the
   * film's u range and v range (left, right, bottom, top) on the camera frame's [0, 1]^2, before
   * the shift (finite; an empty range: the frame itself, as renders), and the frame's aspect
   * ratio (width / height) that the fisheyes' sensor is fitted to (0: the film's). */
  float panorama_viewplane[4];
  float panorama_frame_aspect;
  /* A perspective camera's zoom over the shutter (Cycles' perspective motion: fov_pre and
   * fov_post, taken at the shutter's opening and closing): the view plane's size there over the
   * centre's, tan(fov / 2) / tan(fov_centre / 2) (> 0; 0 or 1: none). A film position's point on
   * the view plane is interpolated linearly in time between them, as camera_sample_perspective
   * does. Ignored by orthographic and panoramic cameras, as Cycles. */
  float zoom_pre, zoom_post;
} lt_camera_desc;
LT_API int lt_scene_set_camera(lt_scene* scene, const lt_camera_desc* desc);

/* World: colour x strength, optionally multiplied by an equirectangular image (image >= 0),
 * rotated about Z by rotation_z (the core makes it a world program, as below). */
typedef struct lt_world_desc {
  float color[3];
  float strength;
  int image;
  float rotation_z;
  unsigned visibility; /* camera visibility of the background */
} lt_world_desc;
LT_API int lt_scene_set_world(lt_scene* scene, const lt_world_desc* desc);
/* World: the World's Surface as a shader program (lt_shader_program, compiled as a material's),
 * run for each direction a ray leaves the scene in: what it emits (Emission closures: Blender's
 * Background and Emission nodes, summed with their Mix/Add Shader weights) is the radiance
 * arriving from there; BSDF closures give none. The shading point is Cycles' for the background (P and
 * Generated the direction, N and I its reverse, Light Path flags of the ray that escaped).
 * A program that folds to a constant is a constant world (no table); otherwise light sampling
 * follows a map of the program baked on an equirectangular grid of map_resolution x
 * map_resolution / 2 pixels (0: automatic, the largest Environment Texture image's size, else
 * 1024 x 512; at most 8192 wide). visibility: LT_VISIBLE_CAMERA, whether camera rays see it. */
LT_API int lt_scene_set_world_program(lt_scene* scene, const lt_shader_program* program, int map_resolution,
                                      unsigned visibility);
/* The world's light group: 0 none, k > 0 light group k - 1 (lt_instance_desc.lightgroup). */
LT_API int lt_scene_set_world_lightgroup(lt_scene* scene, int lightgroup);

/* ---- volumes (docs/volumes.md) ---------------------------------------------------------------
 * A volume is a list of components, each a volume shader node with Cycles' formulas: Principled
 * Volume (sigma_s = d colour, sigma_t = d (colour + (1 - colour)(1 - sqrt(absorption_color)))),
 * Volume Scatter (sigma_s = d colour), Volume Absorption (sigma_a = d (1 - colour)), Emission
 * (emission only: emission_strength x emission_color); Henyey-Greenstein anisotropy, g > 0
 * forward. The components add, as Cycles adds closures (Add Shader; a Mix Shader's factor is the
 * caller's: it scales each side's density, and an Emission node's strength): sigma_a, sigma_s
 * and emission are summed, and the phase function is the mixture of the components' HG lobes
 * weighted by their sigma_s averaged over RGB (at most 8 distinct anisotropies).
 * Emission (Principled and Emission nodes) is radiance per unit length, not scaled by density:
 * emission_strength x emission_color, plus for Principled Volume with blackbody_intensity > 0:
 * blackbody_tint x (Stefan-Boltzmann / pi x 1e-6) x mix(1, T^4, blackbody_intensity) x the
 * unit-luminance blackbody colour of `temperature` kelvin (Cycles' formula; unclamped as Cycles'
 * Principled Volume: negative green and blue below ~1900 K). Fields after
 * `anisotropy` may be left zero: no emission. Volume objects (lt_scene_add_volume_grid) may read
 * parameters from float grids of their file, as Cycles' volume attributes (an Attribute node
 * feeding the socket): emission_strength_grid, blackbody_intensity_grid and temperature_grid
 * multiply emission_strength, blackbody_intensity and temperature by the grid's value at each
 * point; temperature_attribute (Principled Volume's Temperature Attribute) multiplies the
 * temperature by max(0, its value). NULL or "": the constant. Material and World volumes refuse
 * grid names. */
enum lt_volume_node {
  LT_VOLUME_PRINCIPLED = 0,
  LT_VOLUME_SCATTER = 1,
  LT_VOLUME_ABSORPTION = 2,
  LT_VOLUME_EMISSION = 3
};
typedef struct lt_volume_desc {
  int node; /* lt_volume_node */
  float color[3];
  float density;
  float absorption_color[3]; /* Principled only */
  float anisotropy;
  float emission_strength; /* Principled and Emission */
  float emission_color[3];
  float blackbody_intensity; /* Principled only */
  float blackbody_tint[3];
  float temperature;
  const char* emission_strength_grid; /* Volume objects only (see above) */
  const char* blackbody_intensity_grid;
  const char* temperature_grid;
  const char* temperature_attribute;
} lt_volume_desc;

/* Gives a material a homogeneous medium, the sum of `count` >= 1 components, inside the closed
 * meshes that use it (entered through front faces, left through back faces). null_surface != 0:
 * the material has no Surface output and its boundary is invisible to the integrators that render
 * media, VOLPATH and BIDIRECTIONAL (the add-on exports a Transparent surface for PATH). */
LT_API int lt_scene_set_material_volume(lt_scene* scene, int material, const lt_volume_desc* components, int count,
                                        int null_surface);

/* A World volume: a homogeneous medium (the sum of `count` components) filling the
 * whole scene, active along every ray (it adds to the media of closed meshes the ray is in). As in
 * Cycles 3.4, rays that escape travel an infinite distance through it: the background seen through
 * a world volume with sigma_t > 0 is fully attenuated, and so are shadow rays to the world and to
 * sun lights (they reach infinity). The volumetric and bidirectional integrators see it; its
 * emission is in no light group (as Cycles). Calling it again adds another world medium. */
LT_API int lt_scene_set_world_volume(lt_scene* scene, const lt_volume_desc* components, int count);

/* A Volume object: the float grid `grid` of the .vdb file at `path` (its density multiplies the
 * components' Density, per world unit: the add-on folds Blender's render space into Density and
 * the emission), placed by `transform` (object to world, row-major 3x4) after the grid's own
 * index-to-object transform. `step`: its ray-marching step in world units (0: the grid's smallest
 * world-space voxel edge); a render's volume_step > 0 overrides it. The medium is bounded by the
 * grid; no geometry. Its emission is confined, as Cycles 3.4's, to the region its volume mesh
 * encloses: the 8^3-voxel leaves holding active voxels of the density and emission grids whose
 * |value| >= `clipping` (Blender's Volume Render > Clipping, 0.001 by default) or a face neighbour
 * of one (so a constant Emission Strength fills those leaves, not the grids' bounding box), moved
 * in object space by face_offset / n along each axis, n the voxels across those active voxels'
 * bounding box on that axis (Cycles' face_overlap_avoidance: face_offset = 0.1 x hash_uint_to_float(
 * hash_string(the Volume datablock's name))). Errors: LT_ERROR_IO with the message (missing,
 * unreadable or corrupt file; no such grid, listing those present; a grid that is empty or not a
 * float grid); LT_ERROR_INVALID_ARGUMENT for a negative or non-finite step or clipping, or a
 * non-finite face_offset. */
LT_API int lt_scene_add_volume_grid(lt_scene* scene, const char* path, const char* grid, const float transform[12],
                                    float step, float clipping, float face_offset, const lt_volume_desc* components,
                                    int count, int* out_id);
/* The light group of a Volume object's emission (out_id of lt_scene_add_volume_grid): 0 none, k > 0
 * light group k - 1 (lt_instance_desc.lightgroup). */
LT_API int lt_scene_set_volume_grid_lightgroup(lt_scene* scene, int volume, int lightgroup);
/* A Volume object's motion blur (out_id of lt_scene_add_volume_grid): `steps` (0: none, else 3 to
 * 129, odd) object-to-world transforms of 12 floats, equally spaced over the shutter, placed as
 * lt_scene_add_volume_grid's `transform` (the centre one equal to it) and interpolated as
 * lt_instance_desc.motion_transforms. Each ray looks the grid up through the transform at its
 * time, as Cycles 3.4 blurs a moving Volume object; exact for rigid motion (a scale that changes
 * over the shutter keeps the density per world unit of lt_scene_add_volume_grid). Errors:
 * LT_ERROR_INVALID_ARGUMENT for another kind of volume, a bad count or a step that is not finite
 * or singular. */
LT_API int lt_scene_set_volume_grid_motion(lt_scene* scene, int volume, const float* transforms, int steps);

/* Builds acceleration structures and light samplers. Must be called before rendering. After a
 * commit, adding images, materials, meshes, instances or volumes is refused with LT_ERROR_STATE;
 * the edits below are allowed (for the viewport) and the next commit rebuilds only what they
 * touched. */
LT_API int lt_scene_commit(lt_scene* scene);

/* ---- incremental edits ----------------------------------------------------------------------
 * Allowed before and after lt_scene_commit, but refused (LT_ERROR_STATE) while the scene has a
 * render that is not destroyed: its threads read the scene. After such an edit the scene must be
 * committed again before lt_render_start. What the next commit rebuilds:
 *   lt_scene_set_instance_transform,           the top-level BVH (over the meshes' own BVHs) and
 *   lt_scene_set_instance_motion               the light sampler (emissive triangles move);
 *   lt_scene_set_material, lt_scene_clear_lights / lt_scene_add_light, lt_scene_set_world
 *                                              the light sampler only;
 *   lt_scene_set_instance_values               with a changed visibility the top-level BVH, else
 *                                              nothing and needs no new commit;
 *   lt_scene_set_camera                        nothing, and needs no new commit (renders read the
 *                                              camera when they start).
 * Meshes' BVHs are never rebuilt: a changed mesh needs a new scene. */
LT_API int lt_scene_set_instance_transform(lt_scene* scene, int instance, const float transform[12]);
/* Replaces an instance's transform motion blur: `steps` transforms of 12 floats over the shutter
 * (as lt_instance_desc.motion_transforms and motion_step_count; 0: none, the instance still at its
 * transform). A step that is not finite or not invertible leaves the instance without motion (a
 * warning), as lt_scene_add_instance does. */
LT_API int lt_scene_set_instance_motion(lt_scene* scene, int instance, const float* transforms, int steps);
/* Replaces an instance's ray visibility, Object Info colour and pass index and its object
 * attributes (as the fields of lt_instance_desc: visibility, color, pass_index, attribute_ids,
 * attribute_values, attribute_count); its geometry, materials and the rest stay. */
LT_API int lt_scene_set_instance_values(lt_scene* scene, int instance, unsigned visibility, const float color[4],
                                        int pass_index, const int* attribute_ids, const float* attribute_values,
                                        int attribute_count);
/* Replaces material `material`'s surface program (as lt_scene_add_material); its volume
 * (lt_scene_set_material_volume) and displacement (lt_scene_set_material_displacement) are kept. */
LT_API int lt_scene_set_material(lt_scene* scene, int material, const lt_shader_program* program);
/* Removes every light added with lt_scene_add_light (to add the edited set again). */
LT_API int lt_scene_clear_lights(lt_scene* scene);

/* How often the scene's commits built each structure (for tests and benchmarks), and the mesh
 * lights the last commit found: triangles of emissive materials and the instances holding them. */
typedef struct lt_scene_stats {
  uint64_t mesh_bvh_builds;
  uint64_t top_bvh_builds;
  uint64_t light_sampler_builds;
  uint64_t emissive_triangles;
  uint64_t emissive_instances;
  uint64_t image_bytes;                       /* memory the scene's images hold */
  uint64_t image_texels;                      /* and their texels, all images */
  uint64_t byte_images;                       /* images stored at 8 bits per channel */
  uint64_t world_map_width, world_map_height; /* the world's sampling map (0 x 0: none, a constant world) */
  /* Motion blur: instances that move, meshes that deform, the camera's motion steps (0: still),
   * Volume objects' grids that move (lt_scene_set_volume_grid_motion). A scene with none of them
   * renders exactly as without motion blur. */
  uint64_t motion_instances, motion_meshes, camera_motion_steps, moving_volumes;
} lt_scene_stats;
LT_API int lt_scene_get_stats(const lt_scene* scene, lt_scene_stats* out);

/* ---- rendering ---------------------------------------------------------------------------- */

/* VOLPATH: volumetric path tracing (equals PATH on a scene without media). BIDIRECTIONAL renders
 * media too (both subpaths scatter in them). PATH ignores media. VOLUME_DEBUG: a 2x2 view
 * of the estimators for the same camera rays, each panel a half-size view of the frame: top left
 * transmittance by ray marching, top right by ratio tracking, bottom left distance to the sampled
 * collision (world units, 0 for none) by ray marching, bottom right by delta tracking. */
enum lt_integrator {
  LT_INTEGRATOR_PATH = 0,
  LT_INTEGRATOR_BIDIRECTIONAL = 1,
  LT_INTEGRATOR_VOLPATH = 2,
  LT_INTEGRATOR_VOLUME_DEBUG = 3,
  LT_INTEGRATOR_COUNT = 4
};
enum lt_volume_estimator { LT_VOLUME_RAY_MARCHING = 0, LT_VOLUME_TRACKING = 1 };
enum lt_mis { LT_MIS_POWER = 0, LT_MIS_BALANCE = 1, LT_MIS_UNIFORM = 2 };
enum lt_filter { LT_FILTER_BOX = 0, LT_FILTER_GAUSSIAN = 1, LT_FILTER_BLACKMAN_HARRIS = 2 };
/* Where a sample's random numbers come from: SOBOL_OWEN (default), Sobol' points with hash-based
 * Owen scrambling per pixel and per dimension (low discrepancy, as Cycles' Sobol/PMJ patterns);
 * INDEPENDENT, an independent PCG32 stream per sample. Both depend only on (seed, pixel, sample
 * index), so sample-split parts merge exactly either way. */
enum lt_sample_pattern { LT_PATTERN_SOBOL_OWEN = 0, LT_PATTERN_INDEPENDENT = 1 };

typedef struct lt_render_settings {
  int width, height;
  /* Border / crop window in pixels of the full frame: [x0, x1) x [y0, y1), y from the bottom.
   * All zero: the full frame. */
  int border[4];
  int samples;
  unsigned seed;
  /* Cycles' Sample Offset: the render takes samples [sample_offset, sample_offset + samples) of the
   * sequence a full render would take, so sample-split parts merge into that render (lt_merge_exr). */
  int sample_offset;
  int integrator;
  int max_bounces;
  int diffuse_bounces, glossy_bounces, transmission_bounces, transparent_bounces;
  float clamp_direct, clamp_indirect; /* 0: off */
  int threads;                        /* 0: all cores */
  int filter;                         /* lt_filter */
  float filter_width;                 /* pixels */
  int transparent_background;         /* Film > Transparent: background alpha 0 */
  /* Bidirectional: vertices of the camera subpath after the camera, vertices of the light
   * subpath including the one on the light (1: only the light vertex, which makes BDPT equal to
   * path tracing with next-event estimation, or VOLPATH in a scene with media), and the MIS
   * heuristic (lt_mis). */
  int max_camera_length, max_light_length;
  int mis_heuristic;
  /* Bidirectional strategy view: keep each (s, t) strategy's weighted contribution for path
   * depths s + t - 2 below this (0: off; at most 8). Read with lt_render_read_strategy_grid. */
  int strategy_view_depth;
  /* Volumes: Cycles' volume bounce limit (default 0: single scattering), the estimator for
   * heterogeneous media (lt_volume_estimator; homogeneous media are always exact) and the
   * ray-marching step in world units (0: each Volume object's own step, lt_scene_add_volume_grid). */
  int volume_bounces;
  int volume_estimator;
  float volume_step;
  /* Halting: the render stops at the first of `samples`, `time_limit` seconds of rendering (0:
   * none; the first pass always completes, later passes may be cut mid-way, leaving some pixels
   * one sample short) and the estimated relative error (lt_render_status.rel_error) falling to
   * `noise_target` (e.g. 0.02; 0: none), checked once every pixel has `min_samples`.
   * adaptive != 0 (needs a noise target): a pixel stops sampling once the variance of its mean is
   * below its share of the target, target^2 * (mean over pixels of sum_c R_pc^2). */
  float time_limit;
  float noise_target;
  int adaptive;
  int min_samples;
  /* Passes the film keeps: bits 1 << lt_pass (Combined and Sample Count are always kept; adaptive
   * sampling also keeps what Variance needs). lt_render_settings_default sets every pass but
   * LT_PASS_AO (its rays cost time) and LT_PASS_VECTOR (it needs motion_pass); reading
   * a pass that is not kept is LT_ERROR_STATE. */
  unsigned passes;
  /* Bytes the caller will also allocate for this render (its copies of the passes): added to the
   * core's estimate of the render's memory. lt_render_start refuses with LT_ERROR_OUT_OF_MEMORY
   * and a message giving both when the sum exceeds what the process can allocate (MemAvailable,
   * RLIMIT_AS), before allocating anything. */
  unsigned long long caller_bytes;
  int sample_pattern; /* lt_sample_pattern */
  /* != 0: once rendering stops (at the samples, the time limit or the noise target; not after a
   * cancel, nor with fewer than 2 samples), Combined's RGB is denoised (native/src/denoise/nfor.h:
   * NFOR-style first-order regression on the Denoising passes, cross-filtering the two half
   * images) and LT_PASS_NOISY_IMAGE keeps the image as rendered; the film then keeps the Noisy
   * Image and Denoising passes whatever `passes` says. lt_render_status.rel_error stays the noisy
   * image's estimate. Default 0. */
  int denoise;
  /* The Mist pass, as Cycles (World > Mist Pass): start and depth in world units, falloff the
   * exponent (Quadratic 2, Linear 1, Inverse Quadratic 0.5). Defaults 5, 25, 2 (Blender's). */
  float mist_start, mist_depth, mist_falloff;
  /* Cryptomatte (Cycles' View Layer > Passes > Cryptomatte): the types kept (lt_cryptomatte bits;
   * default 0, nothing kept) and Blender's Levels (pass_cryptomatte_depth, 1 to 16, default 6):
   * ceil(levels / 2) layers of two (id, coverage) pairs each per type. */
  unsigned cryptomatte;
  int cryptomatte_levels;
  /* Light groups (Cycles' Combined_<name> passes): how many (0 to 1024; default 0: none, and no
   * cost) and their names (lightgroup_count strings, the EXR channels' "Combined_<name>.R"). Each
   * is the radiance from the emitters of that group (lightgroup fields); the groups sum to
   * Combined's RGB where every emitter is in one. */
  int lightgroup_count;
  const char* const* lightgroup_names;
  /* Shader AOVs (Cycles' AOV Output node, view_layer.aovs): how many (0 to 1024; default 0), their
   * names and aov_colors[i] != 0 for a colour AOV (RGBA: the colour and the fraction of samples
   * that wrote it), else a value (1 channel). A program's AOV instruction writes AOV `index` of
   * these. EXR channels "<name>.R/G/B/A" or "<name>.X". */
  int aov_count;
  const char* const* aov_names;
  const int* aov_colors;
  /* Cycles' View Layer > Passes > Alpha Threshold: AOVs are written at the surfaces a camera path
   * meets through transparent passes up to the first whose alpha reaches it. Default 0.5. */
  float pass_alpha_threshold;
  /* LT_PASS_AO: the length of its rays (World > Light Settings > AO Distance; default 10). */
  float ao_distance;
  /* != 0: the scene's motion steps (lt_instance_desc, lt_mesh_desc, lt_camera_desc; three each)
   * are the previous frame, this frame and the next, for LT_PASS_VECTOR, not a shutter: every
   * sample is taken at the centre step, nothing blurs. 0 (default): motion steps span the shutter
   * (motion blur) and LT_PASS_VECTOR stays zero, as Cycles' Vector pass with motion blur on. */
  int motion_pass;
  /* With shadow catchers in the scene (lt_instance_desc.shadow_catcher), Cycles' Combined is the
   * matte of the other objects: nonzero (Cycles with the Shadow Catcher pass off, its
   * use_approximate_shadow_catcher) composites the approximated shadow into it, over the world
   * seen behind the catchers unless the background is transparent; zero leaves the catchers
   * transparent, their shadows in LT_PASS_SHADOW_CATCHER. Default 1. */
  int shadow_catcher_approximate;
  /* With `denoise`: 0 (default) denoises once rendering stops, as above. N > 0 (Cycles' viewport
   * denoising, preview_denoising_start_sample) also denoises the image readers see while
   * rendering: from the pass that completes max(N, 2) samples on, each published image is
   * denoised (the first at that pass, later ones paced so that denoising takes at most a quarter
   * of the render's wall time), and lt_render_status.denoised says whether the image being read
   * is; the image once rendering stops is denoised only with at least max(N, 2) samples. */
  int denoise_start_sample;
} lt_render_settings;

LT_API void lt_render_settings_default(lt_render_settings* settings);

/* Starts rendering on the core's own threads and returns at once. The scene must be committed and
 * must outlive the render. */
LT_API int lt_render_start(lt_scene* scene, const lt_render_settings* settings, lt_render** out);

enum lt_render_state { LT_STATE_RUNNING = 0, LT_STATE_DONE = 1, LT_STATE_CANCELLED = 2, LT_STATE_FAILED = 3 };
typedef struct lt_render_status {
  int state;
  int samples_done; /* complete passes over the image */
  int samples_total;
  double elapsed_seconds;
  double remaining_seconds; /* estimate; negative when unknown */
  uint64_t nan_samples;     /* samples discarded: a value not finite or beyond 1e15 in magnitude */
  uint64_t rays;            /* rays traced so far */
  /* Estimated relative error of the Combined image after the last pass: the RMS error relative to
   * the RMS of the converged image, sqrt(E[sum_pc (I_pc - R_pc)^2] / sum_pc R_pc^2) over pixels p
   * and RGB channels c, from two independent half images (each pixel's even- and odd-numbered
   * samples; core/film.h). Negative before 2 passes; +inf when the noise is as large as the
   * image. Pixels with fewer than 2 finite samples are left out (unestimated_pixels). */
  double rel_error;
  int halt_reason;             /* lt_halt_reason */
  uint64_t active_pixels;      /* pixels still sampling (fewer than the region's with adaptive sampling) */
  uint64_t unestimated_pixels; /* pixels left out of rel_error: fewer than 2 finite samples */
  int denoised;                /* != 0: Combined holds the denoised image (settings.denoise); while
                                * rendering, the image read (denoise_start_sample) */
  double denoise_seconds;      /* the denoiser's (last run's) time, included in elapsed_seconds */
} lt_render_status;
enum lt_halt_reason {
  LT_HALT_NONE = 0, /* still running */
  LT_HALT_SAMPLES = 1,
  LT_HALT_TIME_LIMIT = 2,
  LT_HALT_NOISE_TARGET = 3,
  LT_HALT_CANCELLED = 4,
  LT_HALT_FAILED = 5
};
LT_API int lt_render_poll(lt_render* render, lt_render_status* status);

/* Requests cancellation; lt_render_wait returns within the time one pixel's sample takes. When the
 * render failed (state LT_STATE_FAILED, e.g. an allocation on its threads), lt_render_wait returns
 * LT_ERROR_OUT_OF_MEMORY or LT_ERROR_INTERNAL with the reason; its passes stay readable. */
LT_API int lt_render_cancel(lt_render* render);
LT_API int lt_render_wait(lt_render* render);

enum lt_pass {
  LT_PASS_COMBINED = 0,     /* RGBA */
  LT_PASS_DEPTH = 1,        /* 1 channel: distance along the camera axis (Blender's Z) */
  LT_PASS_NORMAL = 2,       /* 3 channels: mean world-space shading normal of the first hits (Cycles) */
  LT_PASS_ALBEDO = 3,       /* 3 channels: colour of the first non-specular hit */
  LT_PASS_VARIANCE = 4,     /* 3 channels: variance of the Combined pixel mean, per channel */
  LT_PASS_SAMPLE_COUNT = 5, /* 1 channel: samples accumulated in the pixel */
  /* Cycles' denoising passes. NOISY_IMAGE: RGBA, Combined as rendered (equal to Combined unless
   * the render is denoised). The Denoising data, means over the pixel's samples of the first
   * hit's: NORMAL (3) the shading normal in camera space (x right, y up, z forward, as Cycles),
   * ALBEDO (3) as LT_PASS_ALBEDO, DEPTH (1) the distance along the camera ray (0: background). */
  LT_PASS_NOISY_IMAGE = 6,
  LT_PASS_DENOISING_NORMAL = 7,
  LT_PASS_DENOISING_ALBEDO = 8,
  LT_PASS_DENOISING_DEPTH = 9,
  /* Cycles 3.4's light passes (RGB; docs/passes.md): the radiance split by the path's first
   * scattering vertex, by closure kind (diffuse, glossy, transmission; a Glass BSDF's reflection is
   * glossy) or a medium (volume); DIRECT: light reaching the camera through that vertex alone,
   * INDIRECT: the rest. Direct and Indirect are read divided by their COLOR (the first hit's
   * closure weights), as Cycles reads them, so (DIRECT + INDIRECT) x COLOR summed over the three
   * kinds, plus VOLUME_*, EMISSION (emitters seen directly) and ENVIRONMENT (the world seen
   * directly) is Combined's RGB. A Direct or Indirect pass keeps its Colour. */
  LT_PASS_DIFFUSE_DIRECT = 10,
  LT_PASS_DIFFUSE_INDIRECT = 11,
  LT_PASS_DIFFUSE_COLOR = 12,
  LT_PASS_GLOSSY_DIRECT = 13,
  LT_PASS_GLOSSY_INDIRECT = 14,
  LT_PASS_GLOSSY_COLOR = 15,
  LT_PASS_TRANSMISSION_DIRECT = 16,
  LT_PASS_TRANSMISSION_INDIRECT = 17,
  LT_PASS_TRANSMISSION_COLOR = 18,
  LT_PASS_VOLUME_DIRECT = 19,
  LT_PASS_VOLUME_INDIRECT = 20,
  LT_PASS_EMISSION = 21,
  LT_PASS_ENVIRONMENT = 22,
  /* Cycles' data passes of the surface the camera path first scatters from: POSITION (3, world,
   * the pixel's first sample's, as Cycles' sample 0; 0 on the background), UV (3: u, v, 1; mean),
   * MIST (1: lt_render_settings' mist; 1 on the background), OBJECT_INDEX and MATERIAL_INDEX (1:
   * pass_index, the first sample's). */
  LT_PASS_POSITION = 23,
  LT_PASS_UV = 24,
  LT_PASS_MIST = 25,
  LT_PASS_OBJECT_INDEX = 26,
  LT_PASS_MATERIAL_INDEX = 27,
  /* Cycles' Ambient Occlusion pass (RGB; docs/passes.md): at the surface the camera path first
   * scatters from, one cosine-distributed ray about its shading normal up to ao_distance; the
   * mean of the throughput there times the ray's transmittance (1 unoccluded, 0 blocked). */
  LT_PASS_AO = 28,
  /* Cycles' Vector pass (4 channels, pixels of the render): at that surface, its motion on the
   * film to the previous frame (x, y: previous - now) and from the next (z, w: now - next), the
   * mean over the samples that hit a surface (0 elsewhere); needs motion_pass (zero without). */
  LT_PASS_VECTOR = 29,
  /* 3 channels: Cycles' Shadow Catcher pass (the catchers' light with the other objects divided by
   * their light without them; 1 where no catcher was seen), kept when the scene has a catcher. */
  LT_PASS_SHADOW_CATCHER = 30,
  LT_PASS_COUNT = 31
};
LT_API int lt_pass_channels(int pass);

/* Copies a pass of the render region (width*height*channels floats, rows bottom to top, as
 * Blender's RenderResult stores them). While rendering only LT_PASS_COMBINED can be read (the
 * image last published, at most 0.25 s old; zeros before the first pass); every other kept pass
 * once the render has stopped (LT_ERROR_STATE before). */
LT_API int lt_render_read_pass(lt_render* render, int pass, float* out, size_t float_count);
/* The same for rows [y0, y0 + rows) of the region only (row 0 at the bottom): width*rows*channels
 * floats, so that a caller copies the image through a buffer of a few rows (the add-on hands
 * Blender its RenderResult in bands). Added without an ABI version bump (still 7). */
LT_API int lt_render_read_pass_rows(lt_render* render, int pass, int y0, int rows, float* out, size_t float_count);

/* The strategy view of a finished (or cancelled) bidirectional render: a grid of RGB images of
 * the region's size, (depth + 2) columns (s = 0, 1, ...) by `depth` rows (path depth s + t - 2,
 * 0 at the top), rows bottom to top. With out == NULL only the grid's size is returned. */
LT_API int lt_render_read_strategy_grid(lt_render* render, float* out, size_t float_count, int* width, int* height);
/* The same for grid rows [y0, y0 + rows) only (width*rows*3 floats; the size from the call above
 * with out == NULL), read through a few rows' buffer. Added without an ABI version bump (still 7). */
LT_API int lt_render_read_strategy_grid_rows(lt_render* render, int y0, int rows, float* out, size_t float_count);
/* Rows [y0, y0 + rows) of light group `group`'s pass (RGB, width*rows*3 floats; as
 * lt_render_read_pass_rows, read between passes while rendering). */
LT_API int lt_render_read_lightgroup_rows(lt_render* render, int group, int y0, int rows, float* out,
                                          size_t float_count);
/* Rows [y0, y0 + rows) of shader AOV `index` (width*rows*4 floats for a colour AOV, *1 for a
 * value; as lt_render_read_pass_rows). */
LT_API int lt_render_read_aov_rows(lt_render* render, int index, int y0, int rows, float* out, size_t float_count);

/* A Cryptomatte layer of rows [y0, y0 + rows) (Cycles' CryptoObject00, CryptoObject01, ...):
 * width*rows*4 floats, per pixel id, coverage, id, coverage, the pixel's ids sorted by coverage
 * (the mean over its samples of the first hit's throughput), largest first; id 0 and coverage 0
 * in unused slots. type: one lt_cryptomatte bit the render keeps; layer < ceil(levels / 2). As
 * lt_render_read_pass_rows for when it can be read. */
enum lt_cryptomatte { LT_CRYPTOMATTE_OBJECT = 1, LT_CRYPTOMATTE_MATERIAL = 2, LT_CRYPTOMATTE_ASSET = 4 };
LT_API int lt_render_read_cryptomatte_rows(lt_render* render, int type, int layer, int y0, int rows, float* out,
                                           size_t float_count);

LT_API void lt_render_destroy(lt_render* render);

/* Writes the given render's passes to a 32-bit float OpenEXR file (written to a temporary file
 * beside it and renamed: an existing file is replaced only by a complete one). The header records
 * lantern/sample_ranges ("a-b": samples [a, b)), lantern/samples, seed, integrator and resolution.
 * attributes: NULL, or key, value, key, value, ..., NULL: extra string attributes for the header
 * (e.g. "lantern/scene", an identity of the scene that lt_merge_exr compares). */
LT_API int lt_render_write_exr(lt_render* render, const char* path);
LT_API int lt_render_write_exr_attributes(lt_render* render, const char* path, const char* const* attributes);

/* Merges sample-split parts written by lt_render_write_exr (or earlier merges) into out_path: per
 * pixel, the sample-count-weighted average of every pass (Depth: the minimum; Sample Count: the
 * sum; Variance: pooled over the parts), equal to one render of all the parts' samples up to float
 * rounding. Refused with LT_ERROR_INVALID_ARGUMENT and a message naming the part when the parts
 * disagree (resolution, channels, scene, seed, integrator), their sample ranges overlap, or a part
 * has no recorded sample counts; LT_ERROR_IO for unreadable files. Nothing is written on failure. */
LT_API int lt_merge_exr(const char* out_path, const char* const* part_paths, int part_count);

#ifdef __cplusplus
}
#endif

#endif
