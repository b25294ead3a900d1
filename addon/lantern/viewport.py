"""Viewport rendering without Blender's GPU: the viewport's camera, and a session that keeps one
core scene per viewport, applies depsgraph edits to it incrementally and refines progressively.

Edits and what they cost (lantern.h, incremental edits):
  object moved (transform)        new instance transforms, top-level BVH only; no mesh export
  material edited                 that material's nodes, light sampler only; no BVH
  light edited or moved           the lamps again, light sampler only; no BVH
  camera / view moved, resized    nothing in the scene: a new render
  render settings changed         a new render
  geometry, world, anything else  a new scene (full export)
"""

import time
import weakref

import numpy as np

from . import core
from .scene_sync import SceneSync

# Progressive stages after each change, as Cycles' viewport refines its resolution: one sample at
# a reduced resolution, one at each finer one needed, then the full resolution up to the viewport's
# sample count. Every stage is chosen from the measured cost of a pixel sample (_measure): the first
# is the finest of DIVIDERS (per side) whose pass is predicted to take at most START_SECONDS
# (START_DIVIDER while no cost is known); each next one the finest whose pass is predicted to take
# at most REFRESH_SECONDS, and at least twice finer, so that a slow integrator (BDPT: about 0.5 s
# a full pass of the Cornell box at 640 x 360 on 2 cores) still shows an image within about
# REFRESH_SECONDS of the previous one until the full resolution's first pass.
DIVIDERS = (2, 4, 8, 16)
START_DIVIDER = 4
START_SECONDS = 0.03
REFRESH_SECONDS = 0.25
HALF_FLOAT_MAX = 65504.0  # larger values would become Inf in the RGBA16F texture


def view_camera(region_data, width, height):
    """set_camera keywords for what a 3D view region shows, from its projection and view
    matrices (this covers perspective, orthographic and camera views with zoom and offset).

    With sensor fit Horizontal and a 36 mm sensor, Lantern's view plane at unit distance spans
    x in [(shift_x - 1/2) 36/f, (shift_x + 1/2) 36/f]; an OpenGL projection P maps it to
    [(P02 - 1)/P00, (P02 + 1)/P00], hence f = 18 P00 and shift_x = P02 / 2 (orthographic:
    ortho_scale = 2/P00, shift_x = -P03/2); shift_y is in the same units (of the width).
    """
    P = np.array(region_data.window_matrix, dtype=np.float64)
    to_world = np.linalg.inv(np.array(region_data.view_matrix, dtype=np.float64))
    kw = dict(sensor_width=36.0, sensor_height=36.0 * height / max(width, 1),
              sensor_fit=core.SENSOR_HORIZONTAL)
    if region_data.is_perspective:
        near = P[2, 3] / (P[2, 2] - 1.0)
        far = P[2, 3] / (P[2, 2] + 1.0)
        kw.update(type=core.CAMERA_PERSPECTIVE, focal_length=18.0 * P[0, 0],
                  shift_x=0.5 * P[0, 2], shift_y=0.5 * P[1, 2] * P[0, 0] / P[1, 1],
                  clip_start=max(near, 1e-6), clip_end=far)
    else:
        near = (P[2, 3] + 1.0) / P[2, 2]
        far = (P[2, 3] - 1.0) / P[2, 2]
        # Orthographic views clip behind their origin (negative near): move the origin back.
        z = to_world[:3, 2] / np.linalg.norm(to_world[:3, 2])
        to_world[:3, 3] += z * (-near)
        kw.update(type=core.CAMERA_ORTHOGRAPHIC, ortho_scale=2.0 / P[0, 0],
                  shift_x=-0.5 * P[0, 3], shift_y=-0.5 * P[1, 3] * P[0, 0] / P[1, 1],
                  clip_start=0.0, clip_end=far - near)
    kw["transform"] = to_world[:3].astype(np.float32)
    return kw


def with_camera_lens(kw, camera_object, depsgraph):
    """view_camera's keywords for a view through a perspective camera, plus its depth of field
    (Cycles shows it there): the focus distance as for renders, and the F-stop scaled by the
    view's focal length over the camera's, so that the aperture radius (focal length / 2 F-stop)
    is the camera's."""
    from .export.camera import focus_distance
    if camera_object is None or camera_object.type != 'CAMERA' or kw.get("type") != core.CAMERA_PERSPECTIVE:
        return kw
    cam = camera_object.data
    if cam.type != 'PERSP' or not cam.dof.use_dof:
        return kw
    distance = focus_distance(depsgraph, camera_object.evaluated_get(depsgraph))
    if not distance > 0:
        return kw
    return dict(kw, use_dof=True, focus_distance=distance,
                aperture_fstop=cam.dof.aperture_fstop * kw["focal_length"] / cam.lens,
                aperture_blades=cam.dof.aperture_blades, aperture_rotation=cam.dof.aperture_rotation,
                aperture_ratio=cam.dof.aperture_ratio)


def with_camera_panorama(kw, camera_object, depsgraph, region_data, report):
    """view_camera's keywords for a view through a panoramic camera: the camera's panorama (as
    renders export it, depth of field included) on the part of the camera's frame that the region
    covers, as Cycles maps its viewport to the camera border (pano_viewplane); the fisheyes'
    sensor fitted to the frame. Blender draws a panoramic camera's view as a perspective one of
    its lens and frame (kw's projection, from the region's window matrix)."""
    from .export.camera import camera_keywords
    if camera_object is None or camera_object.type != 'CAMERA' or camera_object.data.type != 'PANO':
        return kw
    pano = camera_keywords(depsgraph, camera_object, report)
    if pano.get("type") != core.CAMERA_PANORAMA:
        return kw  # reported: rendered as perspective
    rd = depsgraph.scene.render
    frame = np.array(camera_object.evaluated_get(depsgraph).calc_matrix_camera(
        depsgraph, x=rd.resolution_x, y=rd.resolution_y, scale_x=rd.pixel_aspect_x, scale_y=rd.pixel_aspect_y),
        dtype=np.float64)
    region = np.array(region_data.window_matrix, dtype=np.float64)

    def on_frame(ndc, axis):
        # The region's NDC to the view plane at unit distance (view_camera's docstring), to the
        # frame's NDC, to [0, 1] across the frame.
        plane = (ndc + region[axis, 2]) / region[axis, axis]
        return 0.5 * (frame[axis, axis] * plane - frame[axis, 2] + 1.0)

    pano.update(transform=kw["transform"], panorama_frame_aspect=(rd.resolution_x * rd.pixel_aspect_x) /
                (rd.resolution_y * rd.pixel_aspect_y),
                panorama_viewplane=(on_frame(-1.0, 0), on_frame(1.0, 0), on_frame(-1.0, 1), on_frame(1.0, 1)))
    return pano


def _same_camera(a, b):
    if a is None or b is None or a.keys() != b.keys():
        return False
    return all(np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k]
               for k in a)


# Every live session, for tests and benchmarks that drive a real viewport.
SESSIONS = weakref.WeakSet()


class ViewportSession(SceneSync):
    """One viewport's core scene (kept by SceneSync) and its progressive render. Not
    thread-bound: call from view_update / view_draw (Blender's main thread)."""

    def __init__(self, report):
        super().__init__(report)
        SESSIONS.add(self)
        self.render = None
        self.divider = START_DIVIDER  # of the running render's resolution per side (1: full)
        self.first_divider = None     # the first stage's, after the last change
        self.camera = None
        self.size = (0, 0)
        self.settings_key = None
        self.dirty = True          # the render must (re)start
        self.error = None
        self.pixels = None         # latest Combined image, (h, w, 4) float32, rows bottom to top
        self.version = 0           # bumps whenever pixels change
        self.samples = (0, 0)      # (done, total) of the displayed stage
        self.shown_divider = None  # the divider of the stage the pixels come from (1: full resolution)
        self.status = None         # core status of the render the pixels come from
        self.pixel_seconds = None  # measured seconds per pixel and sample (_measure)
        self._cost = (None, 0)     # (the settings it was measured with, pixel samples it comes from)
        self._shown = None         # (render serial, samples done, state) the pixels come from
        self.changed_at = time.monotonic()
        self.first_image_seconds = None   # from the last change to the first image of it
        self.counters["restarts"] = 0

    def sync(self, depsgraph):
        """Brings the core scene up to date with the depsgraph (view_update)."""
        try:
            self.sync_scene(depsgraph)
            self.error = None
        except core.LanternError as e:
            self.error = str(e)
            self.report({'ERROR'}, self.error)

    # -- view and render -----------------------------------------------------------------------

    def set_view(self, camera, width, height):
        """The region's camera and size (view_draw); restarts the render when they change."""
        if self.scene is None:
            return
        if (width, height) != self.size or not _same_camera(camera, self.camera):
            self._stop()
            self.scene.set_camera(**camera)
            self.camera = camera
            self.size = (width, height)
            self._changed()

    def _before_edit(self):
        self._stop()

    def _changed(self):
        self.dirty = True
        self.changed_at = time.monotonic()
        self.first_image_seconds = None
        # The pixels stay on screen until the new render has some; what they show is stale.
        self.shown_divider = None
        self.samples = (0, 0)
        self.status = None

    def update(self, settings):
        """Starts or advances the progressive render and picks up its newest image. settings:
        render_settings keywords for the full viewport (width, height, samples, ...). Returns
        True while the render is refining (the caller keeps redrawing)."""
        if self.scene is None or self.size[0] <= 0 or self.size[1] <= 0:
            return False
        key = tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in settings.items()))
        if key != self.settings_key:
            self.settings_key = key
            self._stop()
            self.dirty = True
        if self.dirty:
            self.dirty = False
            self.divider = self.first_divider = self._fit(self._finest(START_SECONDS))
            self._start(settings)
        st = self.render.poll()
        self._measure(st, settings)
        # Also once it stops: the final image may be newer than the last published one (a
        # denoised one, say) at the same sample count.
        if st.samples_done > 0 and self._shown != (self.counters["restarts"], st.samples_done, st.state):
            self._read(st)
        if st.state == core.STATE_FAILED:
            self.error = "Lantern viewport render failed"
            return False
        if st.state != core.STATE_RUNNING and self.divider > 1:
            self.divider = self._fit(min(self._finest(REFRESH_SECONDS), self.divider // 2))
            self._start(settings)
            return True
        return st.state == core.STATE_RUNNING

    def _finest(self, seconds):
        """The finest divider (1: full resolution) whose one-sample pass is predicted to take at
        most `seconds`; START_DIVIDER while no cost is known."""
        if self.pixel_seconds is None:
            return START_DIVIDER
        w, h = self.size
        return next((d for d in (1,) + DIVIDERS if (w // d) * (h // d) * self.pixel_seconds <= seconds),
                    DIVIDERS[-1])

    def _fit(self, divider):
        """A view too small to reduce four times over renders at full resolution at once."""
        return divider if min(self.size) >= 4 * divider else 1

    def _measure(self, st, settings):
        """Seconds per pixel and sample of the running render, kept if it comes from at least as
        many pixel samples as the kept figure or from a full-resolution pass (small renders pay
        their start-up over few pixels and overstate the cost); forgotten when the settings that
        set the cost (integrator, bounces, ...) change."""
        if st.samples_done <= 0:
            return
        key = tuple(sorted((k, str(v)) for k, v in settings.items() if k not in ("width", "height", "samples")))
        w, h = self.render.region_size
        work = st.samples_done * w * h
        kept_key, kept_work = self._cost
        if key != kept_key or work >= min(kept_work, self.size[0] * self.size[1]):
            self.pixel_seconds = st.elapsed_seconds / work
            self._cost = (key, work)

    def _start(self, settings):
        self._stop()
        s = dict(settings)
        s["passes"] = 1 << core.PASS_COMBINED  # the viewport shows Combined only: no other film memory
        if self.divider > 1:
            # One sample: nothing to denoise (the film then keeps no denoising features).
            s.update(width=max(1, s["width"] // self.divider), height=max(1, s["height"] // self.divider),
                     samples=1, denoise=0)
        self.render = core.Render(self.scene, s).start()
        self.counters["restarts"] += 1

    def _read(self, st):
        w, h = self.render.region_size
        buf = self.render.read_pass(core.PASS_COMBINED).reshape(h, w, 4)
        np.minimum(buf, HALF_FLOAT_MAX, out=buf)
        self.pixels = buf
        self.version += 1
        self.samples = (st.samples_done, st.samples_total)
        self.status = st
        self.shown_divider = self.divider
        self._shown = (self.counters["restarts"], st.samples_done, st.state)
        if self.first_image_seconds is None:
            self.first_image_seconds = time.monotonic() - self.changed_at

    def _stop(self):
        if self.render is not None:
            self.render.close()
            self.render = None
            self._shown = None

    def _full_export(self, depsgraph, camera_object, motion):
        super()._full_export(depsgraph, camera_object, motion)
        self.camera = None  # the new scene has none yet

    def _close_scene(self):
        self._stop()
        super()._close_scene()
        self.dirty = True

    def close(self):
        self._close_scene()
        self.pixels = None
