"""The material compiler (addon/lantern/export/nodes): its opcodes against the core's headers, node
groups, reroutes, muted nodes, cycles and unsupported nodes, as a user's trees have them."""
import os
import re

import bpy
import pytest

import build_scenes as bs
from lantern import core
from lantern.export import nodes
from lantern.export.nodes import opcodes

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAMILIES = {"kFamilyShadersBegin": 0, "kFamilyInputsBegin": 32, "kFamilyMathBegin": 64, "kFamilyTexturesBegin": 192}


def core_opcodes():
    """{UPPER_SNAKE name: value} of every kOp enumerator in native/src/shading/*.h."""
    found = {}
    shading = os.path.join(ROOT, "native", "src", "shading")
    for name in sorted(os.listdir(shading)):
        if not name.endswith(".h"):
            continue
        text = open(os.path.join(shading, name)).read()
        for body in re.findall(r"enum \w+Op : uint32_t \{(.*?)\};", text, re.S):
            value = None
            for line in body.split("\n"):
                m = re.match(r"\s*kOp(\w+)(?:\s*=\s*([^,/]+))?,", line)
                if not m:
                    continue
                if m.group(2):
                    expr = m.group(2).strip()
                    base, _, plus = expr.partition("+")
                    value = FAMILIES.get(base.strip(), None)
                    value = int(base) if value is None else value
                    value += int(plus) if plus else 0
                else:
                    value += 1
                found[re.sub(r"(?<!^)(?=[A-Z])", "_", m.group(1)).upper()] = value
    return found


def test_opcodes_match_the_core_headers():
    core_ops = core_opcodes()
    assert len(core_ops) > 40, "the header parser found too few opcodes: %s" % core_ops
    ours = {k: v for k, v in vars(opcodes).items() if k.isupper() and not k.startswith("DIST_")}
    missing = sorted(set(core_ops) - set(ours))
    assert not missing, "opcodes the core has and opcodes.py lacks: %s" % missing
    wrong = {k: (ours[k], core_ops[k]) for k in core_ops if ours[k] != core_ops[k]}
    assert not wrong, "opcodes.py disagrees with the core (ours, core's): %s" % wrong


def _compile(material):
    warnings = []
    c = nodes.Compiler(material.name, None, warnings.append)
    c.compile_surface(material.node_tree.get_output_node('CYCLES'))
    return c, warnings


def _emission_material(name):
    mat, nt, out = bs._material(name)
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    return mat, nt, em


def _group(name, build):
    """A node group with one float input 'x' and one float output 'y' = build(tree, x socket)."""
    g = bpy.data.node_groups.new(name, "ShaderNodeTree")
    g.inputs.new("NodeSocketFloat", "x")
    g.outputs.new("NodeSocketFloat", "y")
    gin = g.nodes.new("NodeGroupInput")
    gout = g.nodes.new("NodeGroupOutput")
    g.links.new(build(g, gin.outputs["x"]), gout.inputs["y"])
    return g


def test_groups_reroutes_and_muted_nodes_fold_to_their_value():
    """Nested groups, a reroute and a muted Math node: the whole tree is constant, so the core
    folds it to one Emission closure whose strength is the tree's value, 2 * (0.25 + 1) = 2.5."""
    bs.reset_file()

    def inner_build(g, x):
        add = g.nodes.new("ShaderNodeMath")
        add.operation = 'ADD'
        add.inputs[1].default_value = 1.0
        g.links.new(x, add.inputs[0])
        return add.outputs[0]

    inner = _group("Inner", inner_build)

    def outer_build(g, x):
        node = g.nodes.new("ShaderNodeGroup")
        node.node_tree = inner
        g.links.new(x, node.inputs["x"])
        muted = g.nodes.new("ShaderNodeMath")
        muted.operation = 'POWER'  # muted: passes its first input through
        muted.mute = True
        g.links.new(node.outputs["y"], muted.inputs[0])
        double = g.nodes.new("ShaderNodeMath")
        double.operation = 'MULTIPLY'
        double.inputs[1].default_value = 2.0
        g.links.new(muted.outputs[0], double.inputs[0])
        return double.outputs[0]

    outer = _group("Outer", outer_build)
    mat, nt, em = _emission_material("Grouped")
    group = nt.nodes.new("ShaderNodeGroup")
    group.node_tree = outer
    group.inputs["x"].default_value = 0.25
    reroute = nt.nodes.new("NodeReroute")
    nt.links.new(group.outputs["y"], reroute.inputs[0])
    nt.links.new(reroute.outputs[0], em.inputs["Strength"])
    c, warnings = _compile(mat)
    assert not warnings, warnings
    scene = bs.new_scene("grouped", resolution=(8, 8), samples=1)
    obj = bs.add_object(scene, "Card", bs.mesh_plane("Card", 0.5), (0.0, 0.0, 0.0))
    bs.assign(obj, mat)
    core_scene = core.Scene()
    mat_id = core_scene.add_material(c.program())
    assert mat_id == 0
    # The folded value, read back through a render of the card would need a camera; instead check
    # the program's arithmetic: the Math instructions are all constant, their result 2.5.
    values = [v for v in c.constants]
    assert any(abs(v - 0.25) < 1e-7 for v in values)
    assert sum(1 for w in c.code if w == opcodes.MATH) >= 2


def test_a_cycle_of_links_is_ignored_as_cycles_ignores_it():
    """Blender marks the links of a cycle invalid (drawn red); Cycles and Lantern skip invalid
    links, so the loop's sockets take their own values and the material compiles."""
    bs.reset_file()
    mat, nt, em = _emission_material("Loop")
    a = nt.nodes.new("ShaderNodeMath")
    b = nt.nodes.new("ShaderNodeMath")
    nt.links.new(a.outputs[0], b.inputs[0])
    nt.links.new(b.outputs[0], a.inputs[0])
    nt.links.new(b.outputs[0], em.inputs["Strength"])
    nt.update_tag()
    bpy.context.view_layer.update()
    assert not all(link.is_valid for link in nt.links), "Blender no longer marks cycles invalid"
    c, warnings = _compile(mat)
    assert c.code, "the material compiled to nothing"


def _instructions(c):
    """(op, inputs, params) of each instruction of a compiled program."""
    out, i = [], 0
    while i < len(c.code):
        op, counts = c.code[i], c.code[i + 1]
        n_in, n_out, n_par = counts & 0xFF, (counts >> 8) & 0xFF, (counts >> 16) & 0xFF
        ins = c.code[i + 2:i + 2 + n_in]
        out.append((op, ins, c.code[i + 2 + n_in + n_out:i + 2 + n_in + n_out + n_par]))
        i += 2 + n_in + n_out + n_par
    return out


def _constant(c, operand):
    return c.constants[operand & 0xFFFFFF]


def test_refraction_bsdf_and_transmission_roughness_compile_as_cycles_reads_them():
    """The Refraction BSDF compiles to its closure with the node's distribution and no warning; the
    Principled BSDF hands its Transmission Roughness to the core with GGX (no "ignored" warning) and
    0 with Multiscatter GGX, whose glass Cycles 3.4 builds from Roughness alone."""
    for dist, param in (("SHARP", opcodes.DIST_SHARP), ("GGX", opcodes.DIST_GGX), ("BECKMANN", opcodes.DIST_BECKMANN)):
        mat = bs._bsdf_material("Refr" + dist, "ShaderNodeBsdfRefraction", (0.8, 0.9, 1.0), distribution=dist,
                                Roughness=0.3, IOR=0.8)
        c, warnings = _compile(mat)
        closures = [(ins, par) for op, ins, par in _instructions(c) if op == opcodes.REFRACTION]
        assert len(closures) == 1 and list(closures[0][1]) == [param], _instructions(c)
        assert _constant(c, closures[0][0][4]) == pytest.approx(0.8)
        assert warnings == [], warnings
    for dist, expected in (("GGX", 0.5), ("MULTI_GGX", 0.0)):
        mat, nt, out = bs._material("PrincipledTR" + dist)
        p = nt.nodes.new("ShaderNodeBsdfPrincipled")
        p.distribution = dist
        p.inputs["Transmission"].default_value = 1.0
        p.inputs["Transmission Roughness"].default_value = 0.5
        nt.links.new(p.outputs[0], out.inputs["Surface"])
        c, warnings = _compile(mat)
        [(ins, _)] = [(ins, par) for op, ins, par in _instructions(c) if op == opcodes.PRINCIPLED]
        assert _constant(c, ins[2 + 18]) == expected  # operands: weight, normal, then _PRINCIPLED's order
        assert not any("Transmission Roughness" in w for w in warnings), warnings


def test_unsupported_node_passes_its_input_through_and_names_itself():
    """A node the compiler does not know: its internal link passes the input through (as a muted
    node would), with a warning naming the node."""
    bs.reset_file()
    mat, nt, em = _emission_material("Unknown")
    odd = nt.nodes.new("ShaderNodeTexPointDensity")  # a texture node Lantern does not compile
    nt.links.new(odd.outputs["Color"], em.inputs["Color"])
    c, warnings = _compile(mat)
    assert any("ShaderNodeTexPointDensity" in w and "Point Density" in w for w in warnings), warnings


def test_shader_to_rgb_is_dropped_as_cycles_drops_it():
    """Shader to RGB: its link dropped (the Emission's own Color stays), with a warning saying that
    Cycles does not render it."""
    bs.reset_file()
    mat, nt, em = _emission_material("ShaderToRGB")
    s2r = nt.nodes.new("ShaderNodeShaderToRGB")
    nt.links.new(nt.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], s2r.inputs["Shader"])
    nt.links.new(s2r.outputs["Color"], em.inputs["Color"])
    c, warnings = _compile(mat)
    assert any("ShaderNodeShaderToRGB" in w and "Cycles does not render" in w for w in warnings), warnings


def test_coverage_script_lists_the_unsupported_nodes(scene_factory, capsys):
    """scripts/node_coverage.py on the unsupported_node scene: it names the Point Density and the
    EEVEE Specular BSDF and nothing Lantern renders."""
    import importlib.util
    scene_factory("unsupported_node")
    spec = importlib.util.spec_from_file_location("node_coverage", os.path.join(ROOT, "scripts", "node_coverage.py"))
    coverage = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(coverage)
    coverage.main()
    out = capsys.readouterr().out
    missing = [line for line in out.splitlines() if "NOT SUPPORTED" in line]
    assert any("ShaderNodeTexPointDensity" in line for line in missing), out
    assert any("ShaderNodeEeveeSpecular" in line for line in missing), out
    assert len(missing) == 2, out


def test_true_displacement_compiles_a_vertex_program_and_needs_a_new_scene_when_changed():
    """Displacement Only and Displacement and Bump: a displacement program (ending in
    SetDisplacement) beside the surface, without the old 'not supported' warning; the surface
    bumps for Both (at the undisplaced point: BumpEval) and not for Displacement Only; a viewport
    edit of the displacement asks for a new scene (vertices move at the first commit only)."""
    from types import SimpleNamespace

    from lantern.export.material import ImageExporter, MaterialExporter

    def ops(code):
        return [op for op, _, _ in _instructions(SimpleNamespace(code=list(code)))]
    for method, bumps in (("DISPLACEMENT", False), ("BOTH", True)):
        mat = bs.true_displacement_material("TrueDisp" + method, (0.5, 0.5, 0.5), method)
        warnings = []
        scene = core.Scene()
        materials = MaterialExporter(scene, lambda _k, t: warnings.append(t), ImageExporter(scene, print))
        assert materials.export(mat) >= 0
        assert not warnings, warnings
        program, method_id = materials._displaced
        assert method_id == (core.DISPLACEMENT_TRUE if method == "DISPLACEMENT" else core.DISPLACEMENT_BOTH)
        assert ops(program[0])[-1] == opcodes.SET_DISPLACEMENT
        surface = ops(materials._translate(mat)[0][0])
        assert (opcodes.BUMP_EVAL in surface) == bumps and (opcodes.SET_NORMAL in surface) == bumps
        assert materials.update(mat)  # unchanged: an edit the committed scene takes
        mat.node_tree.nodes["Displacement"].inputs["Scale"].default_value = 0.7
        assert not materials.update(mat)
        scene.close()


def test_hosek_wilkie_sky_warns_and_coverage_lists_it(capsys):
    """The Sky Texture's Hosek / Wilkie model is not carried: compiling it warns naming the node
    (the export prefixes the material) and renders Preetham's sky (same opcode, type 0), and the
    coverage script lists it; a Nishita sky compiles silently and is not listed."""
    import importlib.util
    from lantern.export.nodes import opcodes as ops
    bs.reset_file()
    for kind in ("HOSEK_WILKIE", "NISHITA"):
        mat, nt, em = _emission_material("Sky_" + kind)
        sky = nt.nodes.new("ShaderNodeTexSky")
        sky.name = "MySky"
        sky.sky_type = kind
        nt.links.new(sky.outputs[0], em.inputs["Color"])
        c, warnings = _compile(mat)
        code = c.program()[0]
        at = code.index(ops.TEX_SKY)
        n_in, n_out = code[at + 1] & 0xff, (code[at + 1] >> 8) & 0xff
        assert code[at + 2 + n_in + n_out] == (0 if kind == "HOSEK_WILKIE" else 2)
        if kind == "HOSEK_WILKIE":
            assert any("MySky" in w and "Hosek" in w for w in warnings), warnings
        else:
            assert warnings == [], warnings
    spec = importlib.util.spec_from_file_location("node_coverage", os.path.join(ROOT, "scripts", "node_coverage.py"))
    coverage = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(coverage)
    coverage.main()
    missing = [line for line in capsys.readouterr().out.splitlines() if "NOT SUPPORTED" in line]
    assert len(missing) == 1 and "Sky_HOSEK_WILKIE" in missing[0] and "MySky" in missing[0], missing
