"""Lantern's RenderEngine: export, start the native render, poll it, fill Blender's passes."""

import time

import bpy
import numpy as np

from . import core
from .export import export_scene

POLL_SECONDS = 0.05        # test_break() and status poll period: cancel acts well within 0.5 s
MIN_UPDATE_SECONDS = 0.2   # progressive image updates at most 5 times a second...
UPDATE_COST_FACTOR = 5.0   # ...and spaced so that copying the image takes at most ~20% of the time

# (Blender pass name, lt_pass, Blender channels, channel ids, type, view layer flag or None)
PASSES = (
    ("Combined", core.PASS_COMBINED, 4, "RGBA", 'COLOR', None),
    ("Depth", core.PASS_DEPTH, 1, "Z", 'VALUE', "use_pass_z"),
    ("Normal", core.PASS_NORMAL, 3, "XYZ", 'VECTOR', "use_pass_normal"),
    ("Albedo", core.PASS_ALBEDO, 3, "RGB", 'COLOR', None),
    ("Variance", core.PASS_VARIANCE, 3, "RGB", 'COLOR', None),
    ("Sample Count", core.PASS_SAMPLE_COUNT, 1, "X", 'VALUE', None),
)

_FILTERS = {
    'BOX': core.FILTER_BOX,
    'GAUSSIAN': core.FILTER_GAUSSIAN,
    'BLACKMAN_HARRIS': core.FILTER_BLACKMAN_HARRIS,
}


def enabled_passes(view_layer):
    return [p for p in PASSES if p[5] is None or getattr(view_layer, p[5], False)]


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


def render_settings(scene, width, height, border):
    lt = scene.lantern
    cycles = getattr(scene, "cycles", None)
    if cycles is not None:
        filter_type = _FILTERS.get(cycles.pixel_filter_type, core.FILTER_BLACKMAN_HARRIS)
        # Cycles ignores the width for the box filter: one pixel.
        filter_width = 1.0 if filter_type == core.FILTER_BOX else cycles.filter_width
    else:
        filter_type, filter_width = core.FILTER_BLACKMAN_HARRIS, 1.5
    integrators = {'PATH': core.INTEGRATOR_PATH, 'BIDIRECTIONAL': core.INTEGRATOR_BIDIRECTIONAL,
                   'VOLPATH': core.INTEGRATOR_VOLPATH, 'VOLUME_DEBUG': core.INTEGRATOR_VOLUME_DEBUG}
    estimators = {'RAY_MARCHING': core.VOLUME_RAY_MARCHING, 'TRACKING': core.VOLUME_TRACKING}
    heuristics = {'POWER': core.MIS_POWER, 'BALANCE': core.MIS_BALANCE, 'UNIFORM': core.MIS_UNIFORM}
    return dict(
        width=width, height=height, border=border,
        samples=lt.samples, seed=lt.seed & 0xFFFFFFFF, sample_offset=lt.sample_offset,
        integrator=integrators[lt.integrator],
        max_bounces=lt.max_bounces, diffuse_bounces=lt.diffuse_bounces,
        glossy_bounces=lt.glossy_bounces, transmission_bounces=lt.transmission_bounces,
        transparent_bounces=lt.transparent_bounces,
        clamp_direct=lt.clamp_direct, clamp_indirect=lt.clamp_indirect,
        threads=lt.threads,
        filter=filter_type, filter_width=filter_width,
        transparent_background=int(scene.render.film_transparent),
        max_camera_length=lt.max_camera_length, max_light_length=lt.max_light_length,
        mis_heuristic=heuristics[lt.mis_heuristic],
        strategy_view_depth=lt.strategy_view_depth if lt.integrator == 'BIDIRECTIONAL' else 0,
        volume_bounces=lt.volume_bounces, volume_estimator=estimators[lt.volume_estimator],
        volume_step=lt.volume_step,
    )


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
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = grid
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return None


def _clock(seconds):
    if seconds < 0:
        return "--:--"
    m, s = divmod(seconds, 60.0)
    h, m = divmod(int(m), 60)
    return ("%d:%02d:%05.2f" % (h, m, s)) if h else ("%02d:%05.2f" % (m, s))


def format_stats(st):
    text = "Sample %d/%d | Elapsed %s" % (st.samples_done, st.samples_total,
                                         _clock(st.elapsed_seconds))
    if st.state == core.STATE_RUNNING:
        text += " | Remaining %s" % _clock(st.remaining_seconds)
    return text


class _PassWriter:
    """Copies core passes into a RenderResult layer's passes (padding channels if needed)."""

    def __init__(self, render, layer, view, passes):
        self.render = render
        self.targets = []
        for name, pass_id, channels, _, _, _ in passes:
            bpass = layer.passes.find_by_name(name, view)
            if bpass is None:
                continue
            core_channels = core.pass_channels(pass_id)
            buf = np.empty(render.pass_size(pass_id), dtype=np.float32)
            pad = None
            if core_channels != channels:
                pad = np.zeros(buf.size // core_channels * channels, dtype=np.float32)
            self.targets.append((name, pass_id, bpass, buf, pad, core_channels, channels))

    def write(self, only=None):
        for name, pass_id, bpass, buf, pad, cc, bc in self.targets:
            if only is not None and name not in only:
                continue
            self.render.read_pass(pass_id, buf)
            if pad is not None:
                n = min(cc, bc)
                pad.reshape(-1, bc)[:, :n] = buf.reshape(-1, cc)[:, :n]
                out = pad
            else:
                out = buf
            # rect is (pixels, channels): Blender 3.4 takes a 2-D array here, not a flat one.
            bpass.rect.foreach_set(out.reshape(-1, bc))


class LanternRenderEngine(bpy.types.RenderEngine):
    bl_idname = 'LANTERN'
    bl_label = 'Lantern'
    bl_use_preview = False
    bl_use_postprocess = True
    bl_use_shading_nodes_custom = False  # edit materials with Blender's shader nodes
    bl_use_eevee_viewport = True         # Material Preview shading uses EEVEE

    def update_render_passes(self, scene=None, renderlayer=None):
        for name, _, channels, chan_id, kind, _ in enabled_passes(renderlayer):
            self.register_pass(scene, renderlayer, name, channels, chan_id, kind)

    def render(self, depsgraph):
        scene = depsgraph.scene
        view_layer = depsgraph.view_layer
        width, height, border = frame_size(scene.render)

        self.update_stats("", "Exporting scene")
        core_scene = None
        render = None
        try:
            core_scene = core.Scene()
            t0 = time.monotonic()
            summary = export_scene(depsgraph, core_scene, self.report,
                                   camera_object=self.camera_override)
            if self.test_break():
                return
            self.update_stats("", "Building acceleration structures")
            core_scene.commit()
            for w in core_scene.warnings():
                self.report({'WARNING'}, w)
            print("Lantern: exported %s in %.2f s" % (summary, time.monotonic() - t0))
            if summary.get("media") and scene.lantern.integrator not in ('VOLPATH', 'VOLUME_DEBUG'):
                self.report({'WARNING'}, "The scene has %d participating medium/media, which only the "
                            "Volumetric Path integrator renders: the %s integrator ignores them"
                            % (summary["media"], scene.lantern.integrator.title()))

            render = core.Render(core_scene, render_settings(scene, width, height, border))
            render.start()
            self._progress(render, view_layer, border)
        except core.LanternError as e:
            self.report({'ERROR'}, str(e))
            print("Lantern: error: %s" % e)
        finally:
            if render is not None:
                render.close()
            if core_scene is not None:
                core_scene.close()

    def _progress(self, render, view_layer, border):
        rw, rh = render.region_size
        passes = enabled_passes(view_layer)
        # Blender clamps the requested size to its render rectangle (the border when there is
        # one): asking for the full frame gives that rectangle's true size to check against.
        fw, fh = render.settings.width, render.settings.height
        result = self.begin_result(0, 0, fw, fh, layer=view_layer.name)
        try:
            if (result.resolution_x, result.resolution_y) != (rw, rh):
                raise core.LanternError(
                    "Render result is %dx%d but Lantern renders %dx%d (border %s)"
                    % (result.resolution_x, result.resolution_y, rw, rh, border))
            writer = _PassWriter(render, result.layers[0], self.active_view_get(), passes)
            cancelled = self._poll_loop(render, result, writer)
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
            LAST_RENDER.clear()
            LAST_RENDER.update(stats=st, settings=render.settings)
            if render.settings.strategy_view_depth > 0:
                # bpy.data must not be touched from the render thread: the image is made on the
                # main thread by a timer.
                LAST_RENDER["strategies"] = render.read_strategy_grid()
                bpy.app.timers.register(_show_strategies, first_interval=0.0)
            self.update_stats("", format_stats(st) + (" | Cancelled" if cancelled else ""))
            self.update_progress(1.0 if st.samples_total <= 0 else
                                 st.samples_done / st.samples_total)
            if st.nan_samples:
                self.report({'WARNING'}, "%d samples were not finite and were discarded"
                            % st.nan_samples)
        finally:
            # Never cancel=True: that would drop the (partial) image.
            self.end_result(result)

    def _poll_loop(self, render, result, writer):
        """Polls until the render ends; returns True if the user cancelled it."""
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
                self.update_result(result)
                self.update_stats("", format_stats(st))
                if st.samples_total > 0:
                    self.update_progress(st.samples_done / st.samples_total)
                cost = time.monotonic() - now
                next_update = time.monotonic() + max(MIN_UPDATE_SECONDS, UPDATE_COST_FACTOR * cost)


classes = (LanternRenderEngine,)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
