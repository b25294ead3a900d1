"""The viewport's machinery without a window: the camera taken from a view's matrices, and the
memory a viewport keeps when it is resized again and again."""
import time
import types

import numpy as np
import pytest

from lantern import core
from lantern.engine import format_stats, render_settings, viewport_denoise_settings
from lantern.export import export_scene
from lantern.viewport import ViewportSession, view_camera, with_camera_lens, with_camera_panorama


def _render(core_scene, width, height, samples=4):
    with core.Render(core_scene, dict(width=width, height=height, samples=samples, seed=3,
                                      threads=2)).start() as r:
        r.wait()
        return r.read_pass(core.PASS_COMBINED).reshape(height, width, 4)


def _camera_view(obj, depsgraph, width, height):
    """What a 3D view looking through camera `obj` holds: Blender's own projection matrix for
    the camera at this size, and the inverse of its world matrix."""
    return types.SimpleNamespace(
        window_matrix=obj.calc_matrix_camera(depsgraph, x=width, y=height),
        view_matrix=obj.matrix_world.inverted(),
        is_perspective=obj.data.type != 'ORTHO')


def _camera_cases():
    # (camera type, shift x, shift y, width, height): landscape, portrait (sensor fit flips to
    # vertical) and orthographic.
    return [('PERSP', 0.1, -0.05, 64, 48), ('PERSP', 0.0, 0.08, 40, 64), ('ORTHO', 0.05, 0.0, 64, 48)]


def test_view_camera_renders_what_the_scene_camera_renders(scene_factory):
    scene = scene_factory("cornell_area")
    cam = scene.camera
    for kind, sx, sy, w, h in _camera_cases():
        cam.data.type = kind
        cam.data.ortho_scale = 2.4
        cam.data.shift_x, cam.data.shift_y = sx, sy
        scene.render.resolution_x, scene.render.resolution_y = w, h
        depsgraph = scene.view_layers[0].depsgraph
        depsgraph.update()
        a, b = core.Scene(), core.Scene()
        try:
            export_scene(depsgraph, a, lambda *m: None)
            export_scene(depsgraph, b, lambda *m: None, state={})  # no camera: the viewport's
            b.set_camera(**view_camera(_camera_view(cam.evaluated_get(depsgraph), depsgraph, w, h), w, h))
            a.commit()
            b.commit()
            ia, ib = _render(a, w, h), _render(b, w, h)
        finally:
            a.close()
            b.close()
        # Same seed, same pixels: identical rays up to float rounding, so nearly every pixel
        # follows the same path. A wrong focal length, shift or fit moves the walls' edges.
        diff = np.abs(ia[..., :3] - ib[..., :3]).mean(axis=2)
        assert (diff < 1e-3).mean() > 0.97, (kind, sx, sy, w, h, (diff < 1e-3).mean())


def test_view_through_a_camera_has_its_depth_of_field(scene_factory):
    """Looking through a camera with depth of field, the viewport's lens is the camera's: the
    same pixels as the render's camera (same seed, same lens samples), and not the pinhole's."""
    scene = scene_factory("cornell_dof")
    cam = scene.camera
    w, h = 48, 48
    scene.render.resolution_x, scene.render.resolution_y = w, h
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    images = []
    for lens in (True, False):
        a, b = core.Scene(), core.Scene()
        try:
            export_scene(depsgraph, a, lambda *m: None)
            export_scene(depsgraph, b, lambda *m: None, state={})
            view = view_camera(_camera_view(cam.evaluated_get(depsgraph), depsgraph, w, h), w, h)
            b.set_camera(**(with_camera_lens(view, cam, depsgraph) if lens else view))
            a.commit()
            b.commit()
            images.append((_render(a, w, h), _render(b, w, h)))
        finally:
            a.close()
            b.close()
    for (ia, ib), expected in zip(images, (True, False)):
        same = (np.abs(ia[..., :3] - ib[..., :3]).mean(axis=2) < 1e-3).mean()
        assert (same > 0.97) == expected, (expected, same)


@pytest.mark.parametrize("name", ["pano_fisheye_equidistant", "pano_cubemap_face"])
def test_view_through_a_panoramic_camera_renders_its_panorama(name, scene_factory):
    """Issue 15: looking through a panoramic camera, the viewport renders the camera's panorama
    on the camera's frame, as Cycles maps its viewport to the camera border: a region that is the
    frame renders the render's pixels (same seed); a region twice as wide shows the frame's image
    in its middle half and, beyond the fisheye's circle, black (beyond the cubemap face, the
    projection continued: the room)."""
    scene = scene_factory(name)
    cam = scene.camera
    w, h = 32, 32
    scene.render.resolution_x, scene.render.resolution_y = w, h
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    view = _camera_view(cam.evaluated_get(depsgraph), depsgraph, w, h)
    wide = types.SimpleNamespace(window_matrix=np.array(view.window_matrix), view_matrix=view.view_matrix,
                                 is_perspective=True)
    wide.window_matrix[0, 0] *= 0.5  # the same centre, twice the width
    wide.window_matrix[0, 2] *= 0.5
    images = []
    for region, rw in ((view, w), (wide, 2 * w)):
        a, b = core.Scene(), core.Scene()
        try:
            export_scene(depsgraph, a, lambda *m: None)
            export_scene(depsgraph, b, lambda *m: None, state={})
            kw = with_camera_panorama(view_camera(region, rw, h), cam, depsgraph, region, lambda *m: None)
            assert kw["type"] == core.CAMERA_PANORAMA
            b.set_camera(**kw)
            a.commit()
            b.commit()
            images.append((_render(a, w, h, samples=16), _render(b, rw, h, samples=16)))
        finally:
            a.close()
            b.close()
    (ia, ib), (_, iw) = images
    same = (np.abs(ia[..., :3] - ib[..., :3]).mean(axis=2) < 1e-3).mean()
    assert same > 0.97, same
    for side in (iw[:, :w // 2 - 2, :3], iw[:, -(w // 2 - 2):, :3]):
        assert np.all(side == 0) if name == "pano_fisheye_equidistant" else side.mean() > 0.05 * ia[..., :3].mean()
    middle, frame = iw[:, w // 2:w // 2 + w, :3].mean(), ia[..., :3].mean()
    assert abs(middle / frame - 1) < 0.05, (middle, frame)


def _rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


def _first_image(session, settings, w, h):
    settings = dict(settings, width=w, height=h)
    while True:
        session.update(settings)
        if session.pixels is not None and session.shown_stage == 1 and session.samples[0] >= 1:
            return
        time.sleep(0.002)


def test_resizing_does_not_leak(scene_factory):
    """A viewport resized through 10 sizes, then 50 more times through the same sizes, each time
    rendered to its first full-resolution pass: at the same size again, the resident memory is
    back where it was (it grows by less than a quarter of keeping one image per resize)."""
    scene = scene_factory("cornell_area")
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    session = ViewportSession(lambda *m: None)
    try:
        session.sync(depsgraph)
        assert session.error is None, session.error
        cam = scene.camera
        base = render_settings(scene, 64, 64, [0, 0, 0, 0])
        base.update(samples=2, threads=2)
        cycle = [(320 + 37 * i, 180 + 21 * i) for i in range(10)]
        sizes = cycle * 6
        rss = []
        for i, (w, h) in enumerate(sizes):
            session.set_view(view_camera(_camera_view(cam, depsgraph, w, h), w, h), w, h)
            _first_image(session, base, w, h)
            if i == 9 or i == len(sizes) - 1:  # the same size: the cycle's last
                rss.append(_rss_mb())
        restarts = session.counters["restarts"]
    finally:
        session.close()
    # One leaked film per resize would keep at least its RGBA float readback (16 bytes/pixel).
    leaked_images_mb = sum(16 * w * h for w, h in sizes[10:]) / 2**20
    growth = rss[1] - rss[0]
    print("RSS after 10 resizes %.1f MB, after 60: %.1f MB (growth %.1f MB; one image kept per "
          "resize would be %.0f MB)" % (rss[0], rss[1], growth, leaked_images_mb))
    assert restarts >= 2 * len(sizes), restarts  # every size rendered (two stages each)
    assert growth < 0.25 * leaked_images_mb, (rss, leaked_images_mb)


def _refine(session, settings):
    """Drives the session until its full-resolution render stops; returns (samples, denoised) of
    every image it read on the way."""
    seen = []
    version = session.version
    while True:
        refining = session.update(settings)
        if session.version != version and session.shown_stage == 1:
            version = session.version
            seen.append((session.samples[0], bool(session.status.denoised)))
        if not refining and session.shown_stage == 1:
            return seen
        time.sleep(0.002)


def test_viewport_denoises_from_the_start_sample(scene_factory):
    """Sampling > Viewport > Denoise with Start Sample 4: the image drawn before 4 samples is the
    noisy one (the same pixels as with denoising off), from 4 on the denoised one, closer to a
    converged image than the noisy one at the same samples; the status line says so."""
    scene = scene_factory("cornell_area")
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    w, h = 48, 48
    session = ViewportSession(lambda *m: None)
    try:
        session.sync(depsgraph)
        assert session.error is None, session.error
        cam = scene.camera.evaluated_get(depsgraph)
        session.set_view(view_camera(_camera_view(cam, depsgraph, w, h), w, h), w, h)
        base = dict(render_settings(scene, w, h, [0, 0, 0, 0]), threads=2)

        def drawn(samples, denoise):
            scene.lantern.use_preview_denoising = denoise
            scene.lantern.preview_denoising_start_sample = 4
            seen = _refine(session, dict(base, samples=samples, **viewport_denoise_settings(scene.lantern)))
            return seen, session.pixels[..., :3].copy(), session.status

        reference = drawn(256, False)[1]
        noisy3, noisy4 = drawn(3, False)[1], drawn(4, False)[1]
        seen3, image3, status3 = drawn(3, True)
        assert not status3.denoised and "denoised" not in format_stats(status3)
        assert np.array_equal(image3, noisy3)
        seen4, image4, status4 = drawn(4, True)
        seen8 = drawn(8, True)[0]
        assert status4.denoised and "denoised" in format_stats(status4), format_stats(status4)
        # Every image read while refining: noisy before the start sample, denoised from it on.
        for samples, denoised in seen3 + seen4 + seen8:
            assert denoised == (samples >= 4), (samples, denoised, seen3, seen4, seen8)

        def mse(a):
            return float(((a - reference) ** 2).mean())
        print("viewport MSE against 256 samples at 4 samples: noisy %.3g, denoised %.3g"
              % (mse(noisy4), mse(image4)))
        assert mse(image4) < 0.5 * mse(noisy4), (mse(image4), mse(noisy4))
    finally:
        session.close()
