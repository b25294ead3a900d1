"""Lantern's RenderEngine: export, start the native render, poll it, fill Blender's passes."""

import time

import bpy
import gpu
import numpy as np
from gpu_extras.presets import draw_texture_2d

from . import core
from .export import export_scene
from .export import cryptomatte
from .export.motion import collect as collect_motion
from .export.world import ao_distance
from .export.camera import export_camera
from .scene_sync import SceneSync, depsgraph_updates
from .viewport import ViewportSession, view_camera, with_camera_lens, with_camera_panorama

REDRAW_SECONDS = 0.05      # while a viewport refines, it is redrawn this often

POLL_SECONDS = 0.05        # test_break() and status poll period: cancel acts well within 0.5 s
MIN_UPDATE_SECONDS = 0.2   # progressive image updates at most 5 times a second...
UPDATE_COST_FACTOR = 5.0   # ...and spaced so that copying the image takes at most ~20% of the time

# (Blender pass name, lt_pass, Blender channels, channel ids, type, view layer flag or None; a
# "scene." flag is one of scene.lantern's). Noisy Image and the Denoising data under Cycles' names
# and flags, so that compositor trees made for Cycles find them.
PASSES = (
    ("Combined", core.PASS_COMBINED, 4, "RGBA", 'COLOR', None),
    ("Depth", core.PASS_DEPTH, 1, "Z", 'VALUE', "use_pass_z"),
    ("Normal", core.PASS_NORMAL, 3, "XYZ", 'VECTOR', "use_pass_normal"),
    ("Albedo", core.PASS_ALBEDO, 3, "RGB", 'COLOR', "lantern_extra_passes"),
    ("Variance", core.PASS_VARIANCE, 3, "RGB", 'COLOR', "lantern_extra_passes"),
    ("Sample Count", core.PASS_SAMPLE_COUNT, 1, "X", 'VALUE', "lantern_extra_passes"),
    ("Noisy Image", core.PASS_NOISY_IMAGE, 4, "RGBA", 'COLOR', "scene.use_denoising"),
    ("Denoising Normal", core.PASS_DENOISING_NORMAL, 3, "XYZ", 'VECTOR', "lantern_denoising_store_passes"),
    ("Denoising Albedo", core.PASS_DENOISING_ALBEDO, 3, "RGB", 'COLOR', "lantern_denoising_store_passes"),
    ("Denoising Depth", core.PASS_DENOISING_DEPTH, 1, "Z", 'VALUE', "lantern_denoising_store_passes"),
    # Cycles' data and light passes, under its names and view-layer toggles (docs/passes.md).
    ("Mist", core.PASS_MIST, 1, "Z", 'VALUE', "use_pass_mist"),
    ("Position", core.PASS_POSITION, 3, "XYZ", 'VECTOR', "use_pass_position"),
    ("UV", core.PASS_UV, 3, "UVA", 'VECTOR', "use_pass_uv"),
    ("IndexOB", core.PASS_OBJECT_INDEX, 1, "X", 'VALUE', "use_pass_object_index"),
    ("IndexMA", core.PASS_MATERIAL_INDEX, 1, "X", 'VALUE', "use_pass_material_index"),
    ("DiffDir", core.PASS_DIFFUSE_DIRECT, 3, "RGB", 'COLOR', "use_pass_diffuse_direct"),
    ("DiffInd", core.PASS_DIFFUSE_INDIRECT, 3, "RGB", 'COLOR', "use_pass_diffuse_indirect"),
    ("DiffCol", core.PASS_DIFFUSE_COLOR, 3, "RGB", 'COLOR', "use_pass_diffuse_color"),
    ("GlossDir", core.PASS_GLOSSY_DIRECT, 3, "RGB", 'COLOR', "use_pass_glossy_direct"),
    ("GlossInd", core.PASS_GLOSSY_INDIRECT, 3, "RGB", 'COLOR', "use_pass_glossy_indirect"),
    ("GlossCol", core.PASS_GLOSSY_COLOR, 3, "RGB", 'COLOR', "use_pass_glossy_color"),
    ("TransDir", core.PASS_TRANSMISSION_DIRECT, 3, "RGB", 'COLOR', "use_pass_transmission_direct"),
    ("TransInd", core.PASS_TRANSMISSION_INDIRECT, 3, "RGB", 'COLOR', "use_pass_transmission_indirect"),
    ("TransCol", core.PASS_TRANSMISSION_COLOR, 3, "RGB", 'COLOR', "use_pass_transmission_color"),
    ("VolumeDir", core.PASS_VOLUME_DIRECT, 3, "RGB", 'COLOR', "cycles.use_pass_volume_direct"),
    ("VolumeInd", core.PASS_VOLUME_INDIRECT, 3, "RGB", 'COLOR', "cycles.use_pass_volume_indirect"),
    ("Emit", core.PASS_EMISSION, 3, "RGB", 'COLOR', "use_pass_emit"),
    ("Env", core.PASS_ENVIRONMENT, 3, "RGB", 'COLOR', "use_pass_environment"),
    ("AO", core.PASS_AO, 3, "RGB", 'COLOR', "use_pass_ambient_occlusion"),
    ("Vector", core.PASS_VECTOR, 4, "XYZW", 'VECTOR', "use_pass_vector"),
    ("Shadow Catcher", core.PASS_SHADOW_CATCHER, 3, "RGB", 'COLOR', "cycles.use_pass_shadow_catcher"),
)

# Cycles' World > Mist Pass falloff as the exponent its film applies (blender/sync.cpp).
MIST_FALLOFF = {'QUADRATIC': 2.0, 'LINEAR': 1.0, 'INVERSE_QUADRATIC': 0.5}


def _pass_enabled(scene, view_layer, flag):
    if flag is None:
        return True
    if flag.startswith("scene."):
        return bool(getattr(scene.lantern, flag[len("scene."):]))
    if flag.startswith("cycles."):
        # The Volume passes' toggles live on the Cycles add-on's view-layer settings.
        return bool(getattr(getattr(view_layer, "cycles", None), flag[len("cycles."):], False))
    return bool(getattr(view_layer, flag, False))


def lightgroup_passes(view_layer):
    """Cycles' light group passes, one per view-layer light group: Combined_<name>, RGB
    (docs/passes.md), read as pass core.LIGHTGROUP_PASS + the group's index."""
    return [("Combined_%s" % g.name, core.LIGHTGROUP_PASS + i, 3, "RGB", 'COLOR', None)
            for i, g in enumerate(getattr(view_layer, "lightgroups", ()))]


def aov_passes(view_layer):
    """Cycles' shader AOV passes, one per valid view-layer AOV under its name: a colour's RGBA (the
    colour and the fraction of samples that wrote it), a value's X (docs/passes.md)."""
    aovs = [a for a in getattr(view_layer, "aovs", ()) if a.is_valid]
    return [(a.name, core.aov_pass(i, a.type == 'COLOR'), 4 if a.type == 'COLOR' else 1,
             "RGBA" if a.type == 'COLOR' else "X", 'COLOR' if a.type == 'COLOR' else 'VALUE', None)
            for i, a in enumerate(aovs)]


def enabled_passes(scene, view_layer):
    return ([p for p in PASSES if _pass_enabled(scene, view_layer, p[5])] + lightgroup_passes(view_layer)
            + aov_passes(view_layer))


def cryptomatte_passes(view_layer):
    """Cycles' Cryptomatte passes the view layer enables: (Blender pass name, lt_cryptomatte bit,
    layer), CryptoObject00, CryptoObject01, ... with ceil(Levels / 2) layers per type."""
    layers = (view_layer.pass_cryptomatte_depth + 1) // 2
    return [("%s%02d" % (prefix, k), bit, k) for prefix, bit, flag in cryptomatte.TYPES
            if getattr(view_layer, flag, False) for k in range(layers)]


def cryptomatte_settings(view_layer, pixels):
    """lt_render_settings' Cryptomatte fields, and the bytes Blender's passes of it hold."""
    passes = cryptomatte_passes(view_layer)
    bits = 0
    for _, bit, _ in passes:
        bits |= bit
    return dict(cryptomatte=bits, cryptomatte_levels=view_layer.pass_cryptomatte_depth), pixels * 16 * len(passes)


def pass_settings(passes, pixels):
    """The render settings for these passes: the core keeps only them (lt_render_settings.passes
    and the light groups' names), and counts what Blender holds besides (caller_bytes) in its
    memory check: the render result's passes (_PassWriter's band buffers and band results are a
    few MiB)."""
    mask = 0
    lightgroups, aovs = [], []
    for p in passes:
        if p[1] >= core.AOV_PASS:
            aovs.append((p[0], p[1] & 1))
        elif p[1] >= core.LIGHTGROUP_PASS:
            lightgroups.append(p[0][len("Combined_"):])
        else:
            mask |= 1 << p[1]
    return dict(passes=mask, lightgroups=lightgroups, aovs=aovs, caller_bytes=pixels * sum(p[2] for p in passes) * 4)


def frame_size(rd):
    """Full frame in pixels, and the border [x0, x1, y0, y1] (all zero: no border) exactly as
    Blender computes them: float32 border times size, truncated (0.7 * 320 is 224, not 223)."""
    width = rd.resolution_x * rd.resolution_percentage // 100
    height = rd.resolution_y * rd.resolution_percentage // 100
    border = [0, 0, 0, 0]
    if rd.use_border:
        f = np.float32
        b = [int(f(rd.border_min_x) * f(width)), int(f(rd.border_max_x) * f(width)),
             int(f(rd.border_min_y) * f(height)), int(f(rd.border_max_y) * f(height))]
        if b != [0, width, 0, height]:
            border = b
    return width, height, border


def frame_seed(scene):
    """The seed, hashed with the frame (and subframe) when Animated Seed is on (as Cycles)."""
    lt = scene.lantern
    seed = lt.seed & 0xFFFFFFFF
    if not lt.use_animated_seed:
        return seed
    return _mix32(_mix32(seed ^ _mix32(scene.frame_current & 0xFFFFFFFF)) ^ int(scene.frame_subframe * 65536))


def _mix32(x):
    """A 32-bit integer hash (Wellons' lowbias32): nearby frames get unrelated seeds."""
    x &= 0xFFFFFFFF
    x ^= x >> 16
    x = (x * 0x7FEB352D) & 0xFFFFFFFF
    x ^= x >> 15
    x = (x * 0x846CA68B) & 0xFFFFFFFF
    return x ^ (x >> 16)


def render_settings(scene, width, height, border):
    lt = scene.lantern
    cycles = getattr(scene, "cycles", None)
    if cycles is not None:
        # Cycles' pixel filter identifiers are the core's lt_filter names.
        filter_type = core.enum_value("lt_filter", cycles.pixel_filter_type)
        # Cycles ignores the width for the box filter: one pixel.
        filter_width = 1.0 if filter_type == core.FILTER_BOX else cycles.filter_width
    else:
        default = core.default_settings()
        filter_type, filter_width = default.filter, default.filter_width
    return dict(
        width=width, height=height, border=border,
        samples=lt.samples, seed=frame_seed(scene), sample_offset=lt.sample_offset,
        time_limit=lt.time_limit, noise_target=lt.noise_target,
        adaptive=int(lt.adaptive and lt.noise_target > 0), min_samples=lt.min_samples,
        # The enum properties' identifiers are the core's names (properties.py).
        integrator=core.enum_value("lt_integrator", lt.integrator),
        max_bounces=lt.max_bounces, diffuse_bounces=lt.diffuse_bounces,
        glossy_bounces=lt.glossy_bounces, transmission_bounces=lt.transmission_bounces,
        transparent_bounces=lt.transparent_bounces,
        clamp_direct=lt.clamp_direct, clamp_indirect=lt.clamp_indirect,
        # Blender's Performance > Threads: Auto-detect resolves to the cores, or to `blender -t N`.
        threads=scene.render.threads,
        filter=filter_type, filter_width=filter_width,
        transparent_background=int(scene.render.film_transparent),
        max_camera_length=lt.max_camera_length, max_light_length=lt.max_light_length,
        mis_heuristic=core.enum_value("lt_mis", lt.mis_heuristic),
        strategy_view_depth=lt.strategy_view_depth if lt.integrator == 'BIDIRECTIONAL' else 0,
        volume_bounces=lt.volume_bounces, volume_estimator=core.enum_value("lt_volume_estimator", lt.volume_estimator),
        volume_step=lt.volume_step,
        sample_pattern=core.enum_value("lt_sample_pattern", lt.sample_pattern),
        denoise=int(lt.use_denoising),
        **mist_settings(scene.world),
        ao_distance=ao_distance(scene.world),
    )


def viewport_integrator(lt):
    """The integrator the viewport renders with (Sampling > Viewport > Integrator)."""
    if lt.viewport_integrator == 'FAST' and lt.integrator == 'BIDIRECTIONAL':
        return 'VOLPATH'
    return lt.integrator


def viewport_settings(scene, width, height):
    """The viewport's render settings: the render's, with the viewport's samples, integrator and
    denoising; it stops at its samples or the noise target, never by the time limit."""
    lt = scene.lantern
    settings = render_settings(scene, width, height, [0, 0, 0, 0])
    settings.update(samples=lt.viewport_samples, strategy_view_depth=0, time_limit=0.0,
                    integrator=core.enum_value("lt_integrator", viewport_integrator(lt)),
                    **viewport_denoise_settings(lt))
    return settings


def format_viewport_stats(session, scene):
    """The viewport's status line: its stages below the full resolution say they refine (they
    stop after their one sample), then format_stats; and which integrator previews when it is
    not the render's."""
    st = session.status
    if session.shown_divider != 1:
        text = "Sample 0/%d | refining at 1/%d resolution" % (scene.lantern.viewport_samples, session.shown_divider)
    else:
        text = format_stats(st)
    integrator = viewport_integrator(scene.lantern)
    if integrator != scene.lantern.integrator:
        names = {item.identifier: item.name for item in scene.lantern.bl_rna.properties["integrator"].enum_items}
        text += " | viewport: %s (render: %s)" % (names[integrator], names[scene.lantern.integrator])
    return text


def viewport_denoise_settings(lt):
    """The viewport's denoising (Sampling > Viewport > Denoise): in place of the render's. The
    core's start sample 0 means a final render's denoising; Cycles' 0 denoises from the start."""
    return dict(denoise=int(lt.use_preview_denoising),
                denoise_start_sample=max(1, lt.preview_denoising_start_sample))


def mist_settings(world):
    """The Mist pass's settings from World > Mist Pass (Blender's defaults without a world)."""
    if world is None:
        return dict(mist_start=5.0, mist_depth=25.0, mist_falloff=2.0)
    m = world.mist_settings
    return dict(mist_start=m.start, mist_depth=m.depth, mist_falloff=MIST_FALLOFF.get(m.falloff, 2.0))


def vector_from_frames(scene, view_layer):
    """Whether the Vector pass is asked for and motion blur is off: its motion then comes from the
    neighbouring frames (export/motion.py). With motion blur on the pass stays zero, as Cycles'."""
    return view_layer.use_pass_vector and not (scene.render.use_motion_blur and view_layer.use_motion_blur)


# What the last render did (status and settings, and the BDPT strategy view when asked for):
# for scripts and benchmarks.
LAST_RENDER = {}

STRATEGY_IMAGE = "Lantern Strategies"


def _show_strategies():
    grid = LAST_RENDER.get("strategies")
    if grid is None:
        return None
    h, w, _ = grid.shape
    image = bpy.data.images.get(STRATEGY_IMAGE)
    if image is None or tuple(image.size) != (w, h):
        if image is not None:
            bpy.data.images.remove(image)
        image = bpy.data.images.new(STRATEGY_IMAGE, w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(grid.ravel())  # RGBA as the core's read gives it: no other copy
    image.update()
    return None


def _clock(seconds):
    if seconds < 0:
        return "--:--"
    m, s = divmod(seconds, 60.0)
    h, m = divmod(int(m), 60)
    return ("%d:%02d:%05.2f" % (h, m, s)) if h else ("%02d:%05.2f" % (m, s))


def format_error(rel_error):
    """The estimated relative error (lt_render_status.rel_error) as a percentage."""
    if rel_error < 0:
        return "rel. error --"
    if rel_error == float("inf"):
        return "rel. error >100%"
    return "rel. error %.2g%%" % (100.0 * rel_error) if rel_error < 0.01 else \
        "rel. error %.1f%%" % (100.0 * rel_error)


def _seconds(t):
    return "%.1f s" % t if t < 10 else "%.0f s" % t


def format_stats(st, pixels=0):
    """Blender's status line: "Sample 12/64 | rel. error 2.3%, 41 s | Remaining 00:12.00"."""
    text = "Sample %d/%d | %s, %s" % (st.samples_done, st.samples_total,
                                       format_error(st.rel_error), _seconds(st.elapsed_seconds))
    if pixels and st.active_pixels < pixels:
        text += " | %.0f%% of pixels sampling" % (100.0 * st.active_pixels / pixels)
    if st.unestimated_pixels:
        text += " | %d pixel(s) without finite samples" % st.unestimated_pixels
    if st.denoised:  # the error above stays the noisy image's (the Noisy Image pass)
        text += " | denoised (%s)" % _seconds(st.denoise_seconds)
    if st.state == core.STATE_RUNNING:
        text += " | Remaining %s" % _clock(st.remaining_seconds)
    elif st.halt_reason in (core.HALT_CANCELLED, core.HALT_FAILED):
        text += " | %s" % core.HALT_NAMES[st.halt_reason].capitalize()
    else:
        text += " | Stopped by %s" % core.HALT_NAMES[st.halt_reason]
    return text


def render_metadata(st, settings):
    """What the image is worth and how it was made: stored with the image as "lantern.*" fields
    (RenderResult stamp data, which Blender writes into EXR and PNG headers; a JSON file beside
    other formats, see write_sidecar)."""
    return {
        "lantern.samples": "%d" % st.samples_done,
        "lantern.rel_error": "%.6g" % st.rel_error,
        "lantern.render_seconds": "%.3f" % st.elapsed_seconds,
        "lantern.halt_reason": core.HALT_NAMES[st.halt_reason],
        "lantern.max_samples": "%d" % settings.samples,
        "lantern.time_limit": "%.6g" % settings.time_limit,
        "lantern.noise_target": "%.6g" % settings.noise_target,
        "lantern.adaptive": "%d" % settings.adaptive,
        "lantern.min_samples": "%d" % settings.min_samples,
        "lantern.seed": "%d" % settings.seed,
        "lantern.integrator": core.enum_name("lt_integrator", settings.integrator),
        "lantern.sample_pattern": core.enum_name("lt_sample_pattern", settings.sample_pattern),
        # rel_error is the noisy image's; "1": Combined is denoised (the noisy one: Noisy Image).
        "lantern.denoised": "%d" % st.denoised,
        "lantern.denoise_seconds": "%.3f" % st.denoise_seconds,
    }


_LIGHT_NAMES = {'POINT': "point", 'SPOT': "spot", 'AREA': "area", 'SUN': "sun"}


def scene_report(summary, settings, warnings, st=None, pixels=0):
    """One report of what the scene used and what Lantern did with it (Info editor and log)."""
    s = settings
    lines = ["Lantern render report"]
    integrator = core.enum_name("lt_integrator", s.integrator)
    if integrator == "BIDIRECTIONAL":
        heuristic = core.enum_name("lt_mis", s.mis_heuristic).lower()
        lines.append("integrator: bidirectional path tracing, every (s, t) strategy, %s-heuristic MIS "
                     "(camera path <= %d, light path <= %d vertices); media scatter on both subpaths"
                     % (heuristic, s.max_camera_length, s.max_light_length))
    elif integrator == "VOLPATH":
        lines.append("integrator: volumetric path tracing, next-event estimation from surfaces and "
                     "media with MIS against BSDF/phase sampling")
    elif integrator == "VOLUME_DEBUG":
        lines.append("integrator: volume debug view (estimator panels)")
    else:
        lines.append("integrator: path tracing, next-event estimation with power-heuristic MIS "
                     "against BSDF sampling")
    kinds = summary.get("light_kinds", {})
    lights = ", ".join("%d %s" % (n, _LIGHT_NAMES.get(k, k.lower())) for k, n in sorted(kinds.items()))
    if summary.get("emissive_triangles"):
        lights = ", ".join(filter(None, (lights, "%d emissive mesh object(s) (%d triangles, two-sided)"
                                         % (summary["emissive_objects"], summary["emissive_triangles"]))))
    lines.append("lights: %s; world: %s" % (lights or "none", summary.get("world") or "none"))
    if summary.get("image_texels"):
        lines.append("texture memory: %.1f MiB for %d image(s), %d of them 8-bit, %d read from their files "
                     "(%.2f bytes per texel)"
                     % (summary["image_bytes"] / 2.0 ** 20, summary.get("images", 0),
                        summary.get("byte_images", 0), summary.get("image_files", 0),
                        summary["image_bytes"] / summary["image_texels"]))
    homogeneous = summary.get("material_media", 0) + summary.get("world_media", 0)
    grids = summary.get("volumes", 0)
    if homogeneous or grids:
        media = []
        if homogeneous:
            media.append("%d homogeneous (closed-form distance sampling and transmittance)" % homogeneous)
        if grids:
            est = ("ray marching, step %s (biased)" % ("%g m" % s.volume_step if s.volume_step > 0
                                                        else "= each object's Step Size or voxel size")
                   if s.volume_estimator == core.VOLUME_RAY_MARCHING else
                   "delta tracking and ratio tracking against per-cell majorants (unbiased)")
            media.append("%d heterogeneous VDB grid(s): %s" % (grids, est))
        if summary.get("emissive_media"):
            media.append("%d emitting (volume emission integrated along camera-path segments: closed "
                         "form in homogeneous media, per step or at every tentative collision in VDB "
                         "grids; never light-sampled, as Cycles 3.4; Bidirectional: strategy s = 0 "
                         "only)" % summary["emissive_media"])
        text = "media: " + "; ".join(media)
        if integrator == "PATH":
            text += " -- IGNORED by this integrator (use Volumetric Path or Bidirectional)"
        lines.append(text)
    else:
        lines.append("media: none")
    if "motion_instances" in summary:  # motion blur or the Vector pass asked for (final renders)
        lines.append(("Vector pass motion (frames -1, +1)" if summary.get("motion_vector_pass") else "motion blur") +
                     ": %d moving object(s), %d deforming mesh(es), %d moving Volume object(s), camera %s "
                     "(counted by the core)"
                     % (summary["motion_instances"], summary["motion_meshes"], summary["moving_volumes"],
                        ("moving, %d steps" % summary["camera_motion_steps"] if summary["camera_motion_steps"]
                         else "still") + (", zooming" if summary.get("camera_zoom") else "")))
    if s.noise_target > 0 or s.time_limit > 0:
        halting = ["%d samples" % s.samples]
        if s.time_limit > 0:
            halting.append("%g s" % s.time_limit)
        if s.noise_target > 0:
            halting.append("rel. error %g%% from %d samples%s" % (100 * s.noise_target, s.min_samples,
                                                                  ", adaptive" if s.adaptive else ""))
        lines.append("halting at the first of: " + ", ".join(halting))
    if warnings:
        lines.append("unsupported input and fallbacks:")
        lines.extend("  " + w for w in warnings)
    else:
        lines.append("unsupported input: none")
    if st is not None:
        lines.append("result: " + format_stats(st, pixels))
    return "\n".join(lines)


# File formats whose headers Blender fills with the render's stamp data (checked by
# tests/blender/test_halting.py): the others get a JSON file beside the image.
METADATA_FORMATS = {'OPEN_EXR', 'OPEN_EXR_MULTILAYER', 'PNG', 'JPEG'}


def write_sidecar(scene, metadata):
    """render_write handler work: a JSON file beside an image whose format keeps no metadata."""
    import json
    import os
    if scene.render.image_settings.file_format in METADATA_FORMATS:
        return None
    # A still goes to the output path as it is, an animation frame gets the frame number: the
    # image just written is whichever of the two is newer.
    framed = scene.render.frame_path(frame=scene.frame_current)
    ext = os.path.splitext(framed)[1]
    still = bpy.path.abspath(scene.render.filepath)
    if scene.render.use_file_extension and not still.lower().endswith(ext.lower()):
        still += ext
    written = [p for p in (framed, still) if os.path.isfile(p)]
    if not written:
        return None
    image = max(written, key=os.path.getmtime)
    path = os.path.splitext(image)[0] + ".lantern.json"
    with open(path, "w") as f:
        json.dump(metadata, f, indent=1, sort_keys=True)
    return path


class _PassWriter:
    """Hands the core's passes to Blender in bands of rows: each band is a RenderResult of its own
    (RenderEngine.begin_result), filled from one band-sized buffer and merged into the render's
    result by end_result, so that what the add-on adds to the film and Blender's result is a band's
    worth of memory, not a frame's (the values are the same: each pixel is copied as it is)."""

    BAND_PIXELS = 1 << 16  # 1 MiB of RGBA floats a band

    def __init__(self, engine, render, layer, view, passes, crypto=()):
        self.engine, self.render, self.layer, self.view = engine, render, layer, view
        self.passes = [(name, pass_id, channels) for name, pass_id, channels, _, _, _ in passes]
        self.crypto = list(crypto)  # cryptomatte_passes(): (name, lt_cryptomatte bit, layer)
        width, height = render.region_size
        self.rows = max(1, min(height, self.BAND_PIXELS // max(width, 1)))
        # One buffer for every pass (Blender copies out of it), and one for padding channels.
        core_floats = max(core.pass_channels(p) for _, p, _ in self.passes)
        self.buffer = np.empty(width * self.rows * core_floats, dtype=np.float32)
        self.pad = np.zeros(width * self.rows * max(4, max(c for _, _, c in self.passes)), dtype=np.float32)

    def write(self, only=None):
        width, height = self.render.region_size
        for y0 in range(0, height, self.rows):
            rows = min(self.rows, height - y0)
            result = self.engine.begin_result(0, y0, width, rows, layer=self.layer, view=self.view)
            try:
                layer = result.layers[0]
                for name, pass_id, bc in self.passes:
                    if only is not None and name not in only:
                        continue
                    bpass = layer.passes.find_by_name(name, self.view)
                    if bpass is None:
                        continue
                    cc = core.pass_channels(pass_id)
                    buf = self.render.read_pass_rows(pass_id, y0, rows, self.buffer[:width * rows * cc])
                    if cc != bc:
                        n = min(cc, bc)
                        out = self.pad[:width * rows * bc].reshape(-1, bc)
                        out[:, :n] = buf.reshape(-1, cc)[:, :n]
                        out[:, n:] = 0.0
                    else:
                        out = buf.reshape(-1, bc)
                    # rect is (pixels, channels): Blender 3.4 takes a 2-D array here, not a flat one.
                    bpass.rect.foreach_set(out)
                for name, bit, k in self.crypto if only is None else ():
                    bpass = layer.passes.find_by_name(name, self.view)
                    if bpass is not None:
                        buf = self.render.read_cryptomatte_rows(bit, k, y0, rows, self.pad[:width * rows * 4])
                        bpass.rect.foreach_set(buf.reshape(-1, 4))
            finally:
                # Never cancel=True: that would drop the (partial) image.
                self.engine.end_result(result)


class LanternRenderEngine(bpy.types.RenderEngine):
    bl_idname = 'LANTERN'
    bl_label = 'Lantern'
    bl_use_preview = True                # material previews render through render()
    bl_use_postprocess = True
    bl_use_shading_nodes_custom = False  # edit materials with Blender's shader nodes
    bl_use_eevee_viewport = True         # Material Preview shading uses EEVEE

    def __init__(self):
        self.session = None
        self._kept = None  # final renders with Persistent Data: the scene kept between frames
        self._texture = None
        self._texture_version = -1
        self._cryptomatte = {}  # the last export's Cryptomatte manifests (export/cryptomatte.py)

    def __del__(self):
        # Blender frees a viewport's engine when the shading mode changes or the view closes.
        # If the engine's data is already gone, the session's core objects free themselves
        # (core.Scene / core.Render __del__) once nothing refers to them.
        try:
            session = self.session
            self._close_kept()
        except (AttributeError, ReferenceError):
            return
        if session is not None:
            _REFINING.discard(session)
            _REFINING_ENGINES.pop(session, None)
            session.close()

    def _close_kept(self):
        if self._kept is not None:
            self._kept.close()
            self._kept = None

    def update_render_passes(self, scene=None, renderlayer=None):
        for name, _, channels, chan_id, kind, _ in enabled_passes(scene, renderlayer):
            self.register_pass(scene, renderlayer, name, channels, chan_id, kind)
        for name, _, _ in cryptomatte_passes(renderlayer):
            self.register_pass(scene, renderlayer, name, 4, "rgba", 'COLOR')  # as Cycles (engine.py)

    def render(self, depsgraph):
        scene = depsgraph.scene
        view_layer = depsgraph.view_layer
        width, height, border = frame_size(scene.render)

        self.update_stats("", "Exporting scene")
        core_scene = None
        render = None
        warnings = []

        def report(level, message):
            warnings.append(message)
            self.report(level, message)
        camera = self.camera_override or depsgraph.scene_eval.camera
        vector = vector_from_frames(scene, view_layer) and not self.is_preview
        persistent = scene.render.use_persistent_data and not self.is_preview and camera is not None
        try:
            t0 = time.monotonic()
            if not persistent:
                self._close_kept()
                core_scene = core.Scene()
            # The frame's depsgraph updates, which a kept scene applies, read before motion blur's
            # sub-frames evaluate the depsgraph again.
            updates = depsgraph_updates(depsgraph) if persistent else None
            # Motion blur (final renders; previews and the viewport render without it, as
            # Cycles'): the shutter's sub-frames sampled first, the scene exported at the
            # shutter's centre, then the frame being rendered restored.
            motion, restore = (None, None) if self.is_preview else \
                collect_motion(self, depsgraph, self.camera_override, report, vector_pass=vector)
            try:
                if persistent:
                    # Persistent Data (as Cycles): the scene stays between frames; each frame applies
                    # the depsgraph's updates and its shutter's motion to it (scene_sync.py).
                    if self._kept is None:
                        self._kept = SceneSync(report)
                    self._kept.report = report
                    self._kept.sync_scene(depsgraph, camera, updates, motion)
                    core_scene, summary = self._kept.scene, dict(self._kept.summary)
                    # This frame's, whether exported or edited.
                    summary["camera_motion"] = motion is not None and motion.camera_moves
                else:
                    summary = export_scene(depsgraph, core_scene, report, camera_object=self.camera_override,
                                           motion=motion)
            finally:
                if restore is not None:
                    restore()
            if not persistent:
                if self.test_break():
                    return
                self.update_stats("", "Building acceleration structures")
                core_scene.commit()
            stats = core_scene.stats()
            self._cryptomatte = summary.pop("cryptomatte", {})
            summary.update(emissive_triangles=stats["emissive_triangles"],
                            emissive_objects=stats["emissive_instances"],
                            image_bytes=stats["image_bytes"], image_texels=stats["image_texels"],
                            byte_images=stats["byte_images"])
            if motion is not None:
                summary.update(motion_vector_pass=motion.vector_pass,
                               motion_instances=stats["motion_instances"], motion_meshes=stats["motion_meshes"],
                               camera_motion_steps=stats["camera_motion_steps"], moving_volumes=stats["moving_volumes"],
                               camera_zoom=motion.zoom is not None)
            if summary.get("world") == "nodes":
                summary["world"] = ("nodes, sampling map %dx%d" % (stats["world_map_width"], stats["world_map_height"])
                                    if stats["world_map_width"] else "nodes, constant")
            for w in core_scene.take_warnings():  # those export did not already report by name
                report({'WARNING'}, w)
            print("Lantern: exported %s in %.2f s" % (summary, time.monotonic() - t0))
            if summary.get("subsurface") and scene.lantern.integrator == 'BIDIRECTIONAL':
                report({'WARNING'}, "Bidirectional renders subsurface scattering in its radius-0 limit (a "
                       "diffuse of the subsurface colour; Path and Volumetric Path render it as Cycles): "
                       "material(s) %s" % ", ".join("'%s'" % n for n in summary["subsurface"]))
            if summary.get("media") and scene.lantern.integrator == 'PATH':
                report({'WARNING'}, "The scene has %d participating medium/media, which the Path "
                       "Tracing integrator ignores: use Volumetric Path or Bidirectional"
                       % summary["media"])

            settings = render_settings(scene, width, height, border)
            region = ((border[1] - border[0]) * (border[3] - border[2])) if any(border) else width * height
            settings.update(pass_settings(enabled_passes(scene, view_layer), region))
            crypto, crypto_bytes = cryptomatte_settings(view_layer, region)
            settings.update(crypto, caller_bytes=settings["caller_bytes"] + crypto_bytes)
            settings["pass_alpha_threshold"] = view_layer.pass_alpha_threshold  # where AOVs are written
            settings["motion_pass"] = int(motion is not None and motion.vector_pass)
            if view_layer.use_pass_vector and not vector and not self.is_preview:
                report({'WARNING'}, "The Vector pass is zero with motion blur on, as Cycles writes it")
            if vector and camera is not None and getattr(camera.data, "type", "") == 'PANO':
                report({'WARNING'}, "The Vector pass stays zero with a panoramic camera (Lantern does not "
                                    "project motion through panoramas; Cycles does)")
            # Cycles approximates the catchers' shadow into Combined unless the pass is on (blender/sync.cpp).
            settings["shadow_catcher_approximate"] = int(not _pass_enabled(scene, view_layer,
                                                                           "cycles.use_pass_shadow_catcher"))
            if self.is_preview:  # material preview: small, few samples, no debug views
                settings.update(samples=scene.lantern.viewport_samples, strategy_view_depth=0)
            if scene.render.use_multiview and not self.is_preview:
                if summary.get("camera_motion"):
                    report({'WARNING'}, "Multiview and stereo renders take each view's camera at the "
                                        "shutter's centre: camera motion blur is off (objects still blur)")
                render, st = self._render_views(depsgraph, core_scene, settings, view_layer, border, report)
            else:
                render = core.Render(core_scene, settings)
                render.start()
                st = self._progress([render], scene, view_layer, border)
            rw, rh = render.region_size
            text = scene_report(summary, render.settings, warnings, st, rw * rh)
            LAST_RENDER["report"] = text
            # With the core's BVH builds so far: what a kept scene rebuilt (tests, benchmarks).
            LAST_RENDER["scene_sync"] = dict(self._kept.counters, mesh_bvh_builds=stats["mesh_bvh_builds"],
                                             top_bvh_builds=stats["top_bvh_builds"]) if persistent else None
            print(text)
            self.report({'INFO'}, text)
        except core.LanternError as e:
            self.report({'ERROR'}, str(e))
            print("Lantern: error: %s" % e)
        finally:
            if render is not None:
                render.close()
            if core_scene is not None and not persistent:
                core_scene.close()

    def _render_views(self, depsgraph, core_scene, settings, view_layer, border, report):
        """Multiview and stereo: every view of the render result, each with its own camera (as
        Cycles: the view's model matrix and shift from Blender, which also picks the camera of a
        multiview view by its suffix) and its own seed. Returns the last view's render (closed)
        and status."""
        scene = depsgraph.scene
        camera_object = self.camera_override or scene.camera
        renders = []
        said = set()

        def report_once(level, message):  # the camera's warnings, once for all views
            if message not in said:
                said.add(message)
                report(level, message)

        def view_render(index, view):
            if renders:
                renders[-1].close()  # the scene's camera can change only once no render reads it
            self.active_view_set(view)
            cam = camera_object
            if cam is not None:
                spherical = self.use_spherical_stereo(cam)
                export_camera(depsgraph, core_scene, report_once, cam,
                              matrix=self.camera_model_matrix(cam, use_spherical_stereo=spherical),
                              shift_x=self.camera_shift_x(cam, use_spherical_stereo=spherical))
            s = dict(settings)
            if index:  # independent noise in each view, as Cycles gives its views
                s["seed"] = (settings["seed"] ^ (0x9E3779B9 * index)) & 0xFFFFFFFF
            render = core.Render(core_scene, s)
            renders.append(render)
            render.start()
            return render
        try:
            st = self._progress(view_render, depsgraph.scene, view_layer, border)
        except BaseException:
            for r in renders:
                r.close()
            raise
        return renders[-1], st

    def _progress(self, renders, scene, view_layer, border):
        """Polls the render of each view into its passes. renders: [the started core.Render] for
        one view (mono), or view_render(index, view name) -> a started render, called for every
        view of the render result (multiview)."""
        passes = enabled_passes(scene, view_layer)
        first = renders[0] if isinstance(renders, list) else None
        # The render's result (its size is the render rectangle: the border when there is one);
        # passes are handed over in bands (_PassWriter), never through a full-frame copy.
        result = self.get_result()
        views = [self.active_view_get()] if first is not None else [v.name for v in result.views]
        for index, view in enumerate(views):
            render = first if first is not None else renders(index, view)
            rw, rh = render.region_size
            if (result.resolution_x, result.resolution_y) != (rw, rh):
                raise core.LanternError(
                    "Render result is %dx%d but Lantern renders %dx%d (border %s)"
                    % (result.resolution_x, result.resolution_y, rw, rh, border))
            writer = _PassWriter(self, render, view_layer.name, view, passes, cryptomatte_passes(view_layer))
            cancelled = self._poll_loop(render, writer)
            try:
                render.wait()
                failed = False
            except core.LanternError as e:
                self.report({'ERROR'}, str(e))
                failed = True
            st = render.poll()
            if st.state == core.STATE_FAILED and not failed:
                self.report({'ERROR'}, "Lantern render failed")
            writer.write()  # all passes, whatever was rendered (cancelled: partial image)
            if cancelled or st.state == core.STATE_FAILED:
                break
        metadata = render_metadata(st, render.settings)
        # Stamp data goes on the render's result, not on a band. Cryptomatte's as Cycles stamps it
        # (blender/session.cpp), so that the Cryptomatte node's Render source finds the manifests.
        crypto = cryptomatte.metadata(getattr(self, "_cryptomatte", {}), view_layer.name + ".",
                                      render.settings.cryptomatte)
        for key, value in list(metadata.items()) + list(crypto.items()):
            result.stamp_data_add_field(key, value)
        LAST_RENDER.clear()
        LAST_RENDER.update(stats=st, settings=render.settings, metadata=metadata,
                           preview=self.is_preview)
        if render.settings.strategy_view_depth > 0:
            # bpy.data must not be touched from the render thread: the image is made on the
            # main thread by a timer.
            LAST_RENDER["strategies"] = render.read_strategy_grid()
            bpy.app.timers.register(_show_strategies, first_interval=0.0)
        self.update_stats("", format_stats(st, rw * rh))
        self.update_progress(1.0 if st.samples_total <= 0 else
                             st.samples_done / st.samples_total)
        if st.nan_samples:
            self.report({'WARNING'}, "%d samples were not finite (or beyond 1e15) and were discarded"
                        % st.nan_samples)
        if st.unestimated_pixels:
            self.report({'WARNING'}, "%d pixel(s) had fewer than 2 finite samples and are left "
                        "out of the noise estimate" % st.unestimated_pixels)
        return st

    def _poll_loop(self, render, writer):
        """Polls until the render ends; returns True if the user cancelled it."""
        rw, rh = render.region_size
        pixels = rw * rh
        next_update = time.monotonic() + MIN_UPDATE_SECONDS
        while True:
            time.sleep(POLL_SECONDS)
            if self.test_break():
                render.cancel()
                return True
            st = render.poll()
            if st.state != core.STATE_RUNNING:
                return False
            now = time.monotonic()
            if now >= next_update:
                writer.write(only=("Combined",))
                self.update_stats("", format_stats(st, pixels))
                if st.samples_total > 0:
                    self.update_progress(st.samples_done / st.samples_total)
                cost = time.monotonic() - now
                next_update = time.monotonic() + max(MIN_UPDATE_SECONDS, UPDATE_COST_FACTOR * cost)

    # ---- viewport ------------------------------------------------------------------------------

    def view_update(self, context, depsgraph):
        if self.session is None:
            self.session = ViewportSession(self.report)
        self.session.sync(depsgraph)
        self.tag_redraw()

    def view_draw(self, context, depsgraph):
        session = self.session
        if session is None:
            return
        region = context.region
        scene = depsgraph.scene
        width, height = region.width, region.height
        try:
            view = view_camera(context.region_data, width, height)
            if context.region_data.view_perspective == 'CAMERA':
                space = context.space_data
                camera = space.camera if space.use_local_camera else scene.camera
                view = with_camera_lens(view, camera, depsgraph)
                # (the scene export reported what the camera lacks: not again at each redraw)
                view = with_camera_panorama(view, camera, depsgraph, context.region_data, lambda *m: None)
            session.set_view(view, width, height)
            refining = session.update(viewport_settings(scene, width, height))
        except core.LanternError as e:
            session.error = str(e)
            refining = False
        if refining:
            _REFINING.add(session)
            _REFINING_ENGINES[session] = self
            if not bpy.app.timers.is_registered(_redraw_refining):
                bpy.app.timers.register(_redraw_refining, first_interval=REDRAW_SECONDS)
        else:
            _REFINING.discard(session)
            _REFINING_ENGINES.pop(session, None)  # no reference that would keep a freed engine
        if session.error:
            self.update_stats("", "Lantern: " + session.error)
        elif session.status is not None:
            self.update_stats("", format_viewport_stats(session, scene))
        else:
            self.update_stats("", "Rendering")
        if session.pixels is None:
            return
        if self._texture is None or self._texture_version != session.version:
            h, w, _ = session.pixels.shape
            data = gpu.types.Buffer('FLOAT', w * h * 4, session.pixels.ravel())
            self._texture = gpu.types.GPUTexture((w, h), format='RGBA16F', data=data)
            self._texture_version = session.version
        gpu.state.blend_set('ALPHA_PREMULT')
        self.bind_display_space_shader(scene)
        draw_texture_2d(self._texture, (0, 0), width, height)  # a low-resolution stage is stretched
        self.unbind_display_space_shader()
        gpu.state.blend_set('NONE')


# Viewport sessions that are still refining and their engines: a timer asks them to redraw
# (the native render never calls back into Python).
_REFINING = set()
_REFINING_ENGINES = {}


def _redraw_refining():
    for session in list(_REFINING_ENGINES):
        if session not in _REFINING:
            del _REFINING_ENGINES[session]
            continue
        try:
            _REFINING_ENGINES[session].tag_redraw()
        except ReferenceError:  # the engine was freed while its render refined: stop it
            _REFINING.discard(session)
            del _REFINING_ENGINES[session]
            session.close()
    return REDRAW_SECONDS if _REFINING_ENGINES else None


@bpy.app.handlers.persistent
def _on_render_write(scene, *args):
    metadata = LAST_RENDER.get("metadata")
    if scene.render.engine == LanternRenderEngine.bl_idname and metadata:
        write_sidecar(scene, metadata)


classes = (LanternRenderEngine,)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.app.handlers.render_write.append(_on_render_write)


def unregister():
    if _on_render_write in bpy.app.handlers.render_write:
        bpy.app.handlers.render_write.remove(_on_render_write)
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
