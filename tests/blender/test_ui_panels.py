"""Lantern's panels and settings: drawn only for Lantern, every property they show exists and
says what it trades, the presets order speed against accuracy, and the settings reach the render."""
import types


import bpy
from lantern import core, engine, properties, ui
from lantern.export import export_scene


class _Layout:
    """Records what a panel's draw() asks for; any layout call returns another recorder."""

    def __init__(self, props):
        self._props = props

    def prop(self, data, name, **kw):
        self._props.append((data, name))

    def __getattr__(self, name):
        return lambda *a, **kw: _Layout(self._props)


def _panels():
    return [c for c in ui.classes if issubclass(c, bpy.types.Panel)]


def test_panels_show_only_for_lantern(scene_factory):
    scene = scene_factory("cornell_area")
    for panel in _panels():
        for engine_id, visible in (('LANTERN', True), ('CYCLES', False), ('BLENDER_EEVEE', False)):
            ctx = types.SimpleNamespace(engine=engine_id, scene=scene, object=scene.objects[0],
                                        light=None, material=None, world=None)
            if panel.bl_context in ("render", "view_layer") and panel.__name__ != \
                    "LANTERN_RENDER_PT_sampling_bidirectional":
                assert bool(panel.poll(ctx)) == visible, (panel.__name__, engine_id)
            elif not visible:
                assert not panel.poll(ctx), (panel.__name__, engine_id)


def test_every_drawn_property_exists_and_says_what_it_trades(scene_factory):
    scene = scene_factory("cornell_area")
    scene.lantern.integrator = 'BIDIRECTIONAL'  # draws the bidirectional sub-panel too
    drawn = []
    for panel in _panels():
        if panel.bl_context != "render":
            continue
        ctx = types.SimpleNamespace(engine='LANTERN', scene=scene)
        fake = types.SimpleNamespace(layout=_Layout(drawn))
        panel.draw(fake, ctx)
        if hasattr(panel, "draw_header"):
            panel.draw_header(fake, ctx)
    names = {name for data, name in drawn if data == scene.lantern}
    for data, name in drawn:
        assert name in data.bl_rna.properties, "panel draws missing property %s.%s" % (data, name)
    # Every Lantern setting is reachable from a panel...
    own = {p.identifier for p in scene.lantern.bl_rna.properties if p.identifier not in ("rna_type", "name")}
    assert own <= names, "settings without a panel: %s" % sorted(own - names)
    # ...and its tooltip names the trade.
    trade = ("faster", "slower", "noise", "bias", "cost", "memory", "longer", "accurate", "cleaner")
    for name in own:
        desc = scene.lantern.bl_rna.properties[name].description.lower()
        assert any(w in desc for w in trade), "tooltip of %s does not say what it trades: %r" % (name, desc)


def test_presets_order_speed_against_accuracy(scene_factory):
    scene = scene_factory("cornell_area")
    values = {}
    for key in ("PREVIEW", "FINAL", "REFERENCE"):
        with bpy.context.temp_override(scene=scene):
            assert bpy.ops.lantern.apply_preset(preset=key) == {'FINISHED'}
        values[key] = {k: getattr(scene.lantern, k) for k in properties.PRESETS[key][2]}
        assert values[key] == properties.PRESETS[key][2]
    p, f, r = values["PREVIEW"], values["FINAL"], values["REFERENCE"]
    for k in ("samples", "max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces"):
        assert p[k] < f[k] < r[k], k
    assert r["clamp_direct"] == r["clamp_indirect"] == 0.0, "Reference must be unbiased (no clamping)"


def test_settings_reach_the_render(scene_factory):
    scene = scene_factory("cornell_area")
    scene.render.resolution_x = scene.render.resolution_y = 32
    lt = scene.lantern
    changes = dict(samples=7, seed=5, max_bounces=3, diffuse_bounces=2, glossy_bounces=1,
                   transmission_bounces=4, transparent_bounces=5, volume_bounces=2,
                   clamp_direct=3.0, clamp_indirect=2.0, volume_step=0.25,
                   max_camera_length=6, max_light_length=2)
    for k, v in changes.items():
        setattr(lt, k, v)
    s = engine.render_settings(scene, 32, 32, [0, 0, 0, 0])
    for k, v in changes.items():
        assert s[k] == v, k
    # Threads come from Blender's Performance > Threads (which `blender -t N` sets to Fixed, N).
    scene.render.threads_mode, scene.render.threads = 'FIXED', 1
    assert engine.render_settings(scene, 32, 32, [0, 0, 0, 0])["threads"] == 1
    scene.render.threads_mode = 'AUTO'  # Blender's count of the machine's threads
    assert engine.render_settings(scene, 32, 32, [0, 0, 0, 0])["threads"] == scene.render.threads >= 1
    # And a setting visibly changes the image (rendered the way render() does: export, then
    # render_settings): no bounces is darker by far more than the noise.
    lt.clamp_direct, lt.clamp_indirect, lt.samples = 0.0, 0.0, 32
    means = {}
    for bounces in (12, 0):
        lt.max_bounces = bounces
        depsgraph = scene.view_layers[0].depsgraph
        depsgraph.update()
        with core.Scene() as cs:
            export_scene(depsgraph, cs, lambda *m: None)
            cs.commit()
            with core.Render(cs, engine.render_settings(scene, 32, 32, [0, 0, 0, 0])).start() as r:
                r.wait()
                means[bounces] = r.read_pass(core.PASS_COMBINED).reshape(-1, 4)[:, :3].mean()
    assert means[0] < 0.9 * means[12], means
