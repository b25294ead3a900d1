"""The engine inside Blender: passes, cancellation, transparent film, warnings for unsupported nodes."""
import time

import numpy as np

import bpy
import render_utils as ru
from lantern import core, engine
from lantern.export import export_scene


def test_every_pass_is_present_and_finite(scene_factory):
    scene = scene_factory("cornell_area")
    layer = scene.view_layers[0]
    layer.use_pass_z = True
    layer.use_pass_normal = True
    out = ru.render(scene, ru.LANTERN, 16, seed=0)
    names = set(out)
    for name in ("Combined", "Depth", "Normal", "Albedo", "Variance", "Sample Count"):
        assert name in names, "pass %s missing; got %s" % (name, sorted(names))
        assert np.isfinite(out[name]).all(), name
    assert out["Combined"][..., :3].mean() > 0.01
    assert np.allclose(out["Sample Count"][..., 0], 16)
    # Depth: every pixel sees the box, nearer than the back wall's distance from the camera.
    assert (out["Depth"][..., 0] > 1.0).all() and (out["Depth"][..., 0] < 6.0).all()


def test_transparent_film_gives_alpha_zero_on_background(scene_factory):
    scene = scene_factory("sun_world")
    scene.render.film_transparent = True
    img = ru.render(scene, ru.LANTERN, 4, seed=0).combined
    alpha = img[..., 3]
    top = alpha[:10]  # the top rows see only the sky
    assert (top == 0).all()
    assert (alpha[-10:] == 1).all()  # the bottom rows see the ground
    assert (img[:10, :, :3] == 0).all()


def test_unsupported_nodes_are_reported_and_fall_back(scene_factory):
    scene = scene_factory("unsupported_node")
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    reports = []
    core_scene = core.Scene()
    try:
        export_scene(depsgraph, core_scene, lambda level, message: reports.append(message))
    finally:
        core_scene.close()
    text = "\n".join(reports)
    assert "ToonMaterial" in text and "Toon" in text, text
    assert "NoiseMaterial" in text and "Noise Texture" in text, text
    # The render still completes with a finite image.
    img = ru.render(scene, ru.LANTERN, 4, seed=0).combined
    assert np.isfinite(img).all()


class _CancellingEngine:
    """Stands in for the RenderEngine in the add-on's poll loop: Esc after `after` seconds."""

    def __init__(self, after):
        self.deadline = time.monotonic() + after
        self.cancelled_at = None

    def test_break(self):
        if time.monotonic() >= self.deadline:
            self.cancelled_at = self.cancelled_at or time.monotonic()
            return True
        return False

    def update_result(self, result):
        pass

    def update_stats(self, a, b):
        pass

    def update_progress(self, p):
        pass


class _NullWriter:
    def write(self, only=None):
        pass


def test_cancel_stops_quickly_and_keeps_a_partial_image(scene_factory):
    scene = scene_factory("cornell_area")
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    core_scene = core.Scene()
    try:
        export_scene(depsgraph, core_scene, lambda level, message: None)
        core_scene.commit()
        settings = engine.render_settings(scene, 96, 96, [0, 0, 0, 0])
        settings["samples"] = 1 << 20
        render = core.Render(core_scene, settings)
        try:
            render.start()
            stub = _CancellingEngine(after=0.5)
            cancelled = engine.LanternRenderEngine._poll_loop(stub, render, None, _NullWriter())
            render.wait()
            stopped = time.monotonic() - stub.cancelled_at
            assert cancelled
            assert stopped < 0.5, "render stopped %.2f s after Esc" % stopped
            st = render.poll()
            assert st.state == core.STATE_CANCELLED
            assert 0 < st.samples_done < st.samples_total
            img = render.read_pass(core.PASS_COMBINED).reshape(96, 96, 4)
            assert np.isfinite(img).all() and img[..., :3].mean() > 0.01
        finally:
            render.close()
    finally:
        core_scene.close()
