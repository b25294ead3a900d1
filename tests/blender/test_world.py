"""World node trees compiled as materials are (issue 13, "World node trees"): what is exported, the
sampling map the core builds, and the warnings naming node and world. Agreement with Cycles of lit
scenes: test_agreement.py (hdri_world, light_path_world, procedural_world); the Environment
Texture node pixel by pixel: test_nodes_inputs.py."""
import pytest

import build_scenes as bs
import render_utils as ru

pytestmark = pytest.mark.skipif(not ru.engine_registered(), reason="Lantern add-on not registered")


def test_constant_world_builds_no_sampling_map(scene_factory):
    """A Background of a constant colour (issue 14: constant worlds sampled without a table)."""
    summary, reports = ru.export(scene_factory("sun_world"))
    assert summary["world"] == "nodes" and not reports, reports
    assert (summary["stats"]["world_map_width"], summary["stats"]["world_map_height"]) == (0, 0)


@pytest.mark.parametrize("name,size", [("hdri_world", (64, 32)), ("procedural_world", (1024, 512))])
def test_world_map_resolution_is_cycles_automatic_one(name, size, scene_factory):
    """Cycles' automatic rule: the Environment Texture image's size, else 1024 x 512."""
    summary, reports = ru.export(scene_factory(name))
    assert not reports, reports
    assert (summary["stats"]["world_map_width"], summary["stats"]["world_map_height"]) == size


def test_manual_world_map_resolution(scene_factory):
    scene = scene_factory("procedural_world")
    scene.world.cycles.sampling_method = "MANUAL"
    scene.world.cycles.sample_map_resolution = 256
    summary, _ = ru.export(scene)
    assert (summary["stats"]["world_map_width"], summary["stats"]["world_map_height"]) == (256, 128)


def test_world_warnings_name_node_and_world():
    """An unsupported node passes its input through or gives 0, a BSDF gives no light in a world
    (Cycles reads only emission there): each reported with the node's and the world's names."""
    bs.reset_file()
    scene = bs.new_scene("odd_world", (16, 16), 1)
    bs.add_camera(scene, (0, -3, 0), (0, 0, 0))
    world = bs.set_world(scene, (0.2, 0.3, 0.4), 1.0)
    world.name = "Odd Sky"
    nt = world.node_tree
    bg = nt.nodes["Background"]
    density = nt.nodes.new("ShaderNodeTexPointDensity")
    nt.links.new(density.outputs["Color"], bg.inputs["Color"])
    add = nt.nodes.new("ShaderNodeAddShader")
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    nt.links.new(bg.outputs[0], add.inputs[0])
    nt.links.new(diffuse.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], nt.nodes["World Output"].inputs["Surface"])
    world.cycles_visibility.glossy = False
    summary, reports = ru.export(scene)
    assert any("World 'Odd Sky'" in r and "glossy off" in r for r in reports), reports
    assert any("World 'Odd Sky'" in r and "'Point Density'" in r and "ShaderNodeTexPointDensity" in r
               for r in reports), reports
    assert any("World 'Odd Sky'" in r and "'Diffuse BSDF'" in r and "no light" in r for r in reports), reports


@pytest.mark.parametrize("node,output", [("ShaderNodeTexCoord", o) for o in
                                         ("Generated", "Normal", "UV", "Object", "Camera", "Window", "Reflection")]
                         + [("ShaderNodeNewGeometry", o) for o in ("Position", "Normal", "Incoming")])
def test_world_shading_point_matches_cycles(node, output, outdir):
    """The background's shading point as Cycles sets it up (shader_setup_from_background: P the
    direction, N and I its reverse, no object): a node output as the Background colour, seen by
    camera rays at pixel centres, pixel by pixel against Cycles (node_cases' bound)."""
    from node_cases import beyond, slope_of

    bs.reset_file()
    scene = bs.new_scene("world_point", resolution=(96, 64), samples=1)
    c = scene.cycles
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.max_bounces = 0
    bs.add_camera(scene, (1.0, -2.0, 0.7), (0.2, 0.3, 0.9), lens=20.0)
    world = bs.set_world(scene, (0.0, 0.0, 0.0), 1.0)
    nt = world.node_tree
    src = nt.nodes.new(node)
    shift = nt.nodes.new("ShaderNodeVectorMath")  # 0.4 x + 0.5: mostly positive, as emission keeps it
    shift.operation = "MULTIPLY_ADD"
    shift.inputs[1].default_value = (0.4, 0.4, 0.4)
    shift.inputs[2].default_value = (0.5, 0.5, 0.5)
    nt.links.new(src.outputs[output], shift.inputs[0])
    nt.links.new(shift.outputs[0], nt.nodes["Background"].inputs["Color"])
    label = "world_%s_%s" % (node[10:].lower(), output.lower())
    lantern = ru.render(scene, ru.LANTERN, 1, outdir=outdir, tag=label + "_lantern").combined[..., :3]
    cycles = ru.render(scene, ru.CYCLES, 1, outdir=outdir, tag=label + "_cycles").combined[..., :3]
    bad, worst = beyond(lantern, cycles, slope_of(cycles))
    if bad.mean() > 0.005:
        ru.write_png("%s/%s_lantern.png" % (outdir, label), lantern)
        ru.write_png("%s/%s_cycles.png" % (outdir, label), cycles)
    assert bad.mean() <= 0.005, "%s: %.2f%% of pixels beyond the bound (worst %.3g x)" % (
        label, 100 * bad.mean(), worst)
