"""The viewport's machinery without a window: the camera taken from a view's matrices, and the
memory a viewport keeps when it is resized again and again."""
import time
import types

import numpy as np
import pytest

from lantern import core
from lantern import viewport
from lantern.engine import (format_stats, format_viewport_stats, render_settings, viewport_denoise_settings,
                            viewport_settings)
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
        if session.pixels is not None and session.shown_divider == 1 and session.samples[0] >= 1:
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
    assert restarts >= len(sizes), restarts  # every size rendered
    assert growth < 0.25 * leaked_images_mb, (rss, leaked_images_mb)


def _refine(session, settings):
    """Drives the session until its full-resolution render stops; returns (samples, denoised) of
    every image it read on the way."""
    seen = []
    version = session.version
    while True:
        refining = session.update(settings)
        if session.version != version and session.shown_divider == 1:
            version = session.version
            seen.append((session.samples[0], bool(session.status.denoised)))
        if not refining and session.shown_divider == 1:
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


def test_viewport_integrator_previews_bidirectional_with_path_tracing(scene_factory):
    """Issue 14: Sampling > Viewport > Integrator. Fast Preview (the default) renders a
    Bidirectional scene's viewport with volumetric path tracing and keeps every other integrator;
    Same as Render keeps Bidirectional. The status line names the preview's integrator when it
    is not the render's."""
    scene = scene_factory("cornell_area")
    lt = scene.lantern
    assert lt.viewport_integrator == 'FAST'
    expected = {('PATH', 'FAST'): 'PATH', ('VOLPATH', 'FAST'): 'VOLPATH', ('BIDIRECTIONAL', 'FAST'): 'VOLPATH',
                ('VOLUME_DEBUG', 'FAST'): 'VOLUME_DEBUG', ('BIDIRECTIONAL', 'RENDER'): 'BIDIRECTIONAL',
                ('PATH', 'RENDER'): 'PATH'}
    for (render, preview), used in expected.items():
        lt.integrator, lt.viewport_integrator = render, preview
        settings = viewport_settings(scene, 64, 48)
        assert settings["integrator"] == core.enum_value("lt_integrator", used), (render, preview)
        assert settings["samples"] == lt.viewport_samples and settings["time_limit"] == 0
        session = types.SimpleNamespace(shown_divider=1, status=types.SimpleNamespace(
            samples_done=3, samples_total=32, rel_error=0.1, elapsed_seconds=1.0, active_pixels=0,
            unestimated_pixels=0, denoised=False, state=core.STATE_RUNNING, remaining_seconds=2.0))
        text = format_viewport_stats(session, scene)
        assert ("viewport: Volumetric Path (render: Bidirectional)" in text) == (used != render), text


def _stages(session, settings, scene):
    """Drives the session until its full-resolution render stops; returns, for every image it
    read, (divider, samples, predicted seconds of that stage's pass from the cost known when it
    started, status line)."""
    seen, version, predicted = [], session.version, {}
    while True:
        if session.render is not None and session.divider not in predicted:
            w, h = session.size
            d = session.divider
            predicted[d] = None if session.pixel_seconds is None else (w // d) * (h // d) * session.pixel_seconds
        refining = session.update(settings)
        if session.version != version:
            version = session.version
            seen.append((session.shown_divider, session.samples[0], predicted.get(session.shown_divider),
                         format_viewport_stats(session, scene)))
        if not refining and session.shown_divider == 1:
            return seen
        time.sleep(0.001)


def test_viewport_refines_through_resolutions_chosen_from_the_measured_cost(scene_factory):
    """Issue 14: after a change the viewport shows one sample at a reduced resolution, then one at
    each finer resolution it needs, then the full resolution up to its samples. Each stage after
    the first at least halves the divider and is the finest whose pass the cost measured so far
    predicts within REFRESH_SECONDS, or half the previous divider; after a camera move the first
    stage is chosen from the cost the first change measured. Bidirectional at 640 x 360, where a
    full pass costs more than the refresh budget on 2 cores (about 0.5 s). The status line of a
    reduced stage says it refines, never "Stopped"."""
    scene = scene_factory("cornell_area")
    scene.lantern.integrator = 'BIDIRECTIONAL'
    scene.lantern.viewport_integrator = 'RENDER'
    scene.lantern.viewport_samples = 3
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    w, h = 640, 360
    session = viewport.ViewportSession(lambda *m: None)
    try:
        session.sync(depsgraph)
        assert session.error is None, session.error
        cam = scene.camera.evaluated_get(depsgraph)
        settings = dict(viewport_settings(scene, w, h), threads=2)
        runs = []
        for shift in (0.0, 0.01):  # the second: a camera move, a new render from a first stage
            view = _camera_view(cam, depsgraph, w, h)
            view.view_matrix[0][3] += shift
            session.set_view(view_camera(view, w, h), w, h)
            runs.append(_stages(session, settings, scene))
        print("stages (divider, samples, predicted seconds):", [[r[:3] for r in run] for run in runs])
        for seen in runs:
            dividers = [d for d, _, _, _ in seen]
            assert dividers[0] > 1 and dividers[-1] == 1 and seen[-1][1] == 3, seen
            stages = [d for i, d in enumerate(dividers) if i == 0 or dividers[i - 1] != d]
            assert all(d <= prev // 2 for prev, d in zip(stages, stages[1:])), seen
            for d, n, _, text in seen:
                if d > 1:
                    assert n == 1 and "refining at 1/%d resolution" % d in text and "Stopped" not in text, text
            assert "Stopped by samples" in seen[-1][3], seen[-1][3]
        stages = [(d, p) for i, (d, _, p, _) in enumerate(runs[1]) if i == 0 or runs[1][i - 1][0] != d]
        assert all(p is not None for _, p in stages), stages
        for (prev, _), (d, p) in zip(stages, stages[1:]):
            assert p <= viewport.REFRESH_SECONDS or d == prev // 2, stages
    finally:
        session.close()
