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
    sky = nt.nodes.new("ShaderNodeTexSky")
    nt.links.new(sky.outputs["Color"], bg.inputs["Color"])
    add = nt.nodes.new("ShaderNodeAddShader")
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    nt.links.new(bg.outputs[0], add.inputs[0])
    nt.links.new(diffuse.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], nt.nodes["World Output"].inputs["Surface"])
    summary, reports = ru.export(scene)
    assert any("World 'Odd Sky'" in r and "'Sky Texture'" in r and "ShaderNodeTexSky" in r for r in reports), reports
    assert any("World 'Odd Sky'" in r and "'Diffuse BSDF'" in r and "no light" in r for r in reports), reports
