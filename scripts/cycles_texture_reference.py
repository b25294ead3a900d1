"""Reference values of Cycles' procedural textures for tests/native/test_textures.cpp.

Renders, with Cycles, a camera-filling plane whose Emission shows one texture output, the texture's
Vector fed by a Combine XYZ of constants (so every pixel has the same value and the pixel filter does
not matter), and writes tests/native/cycles_texture_reference.h. Run:

    blender -b --factory-startup --python scripts/cycles_texture_reference.py
"""
import os
import struct
import sys
import tempfile

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, 'tests', 'native', 'cycles_texture_reference.h')

# Blender node, Lantern opcode name, inputs (socket, 'f' or 'v') and outputs in instruction order.
NODES = {
    'noise': ('ShaderNodeTexNoise', 'kOpTexNoise',
              [('Vector', 'v'), ('W', 'f'), ('Scale', 'f'), ('Detail', 'f'), ('Roughness', 'f'),
               ('Distortion', 'f')], [('Fac', 'f'), ('Color', 'v')]),
    'voronoi': ('ShaderNodeTexVoronoi', 'kOpTexVoronoi',
                [('Vector', 'v'), ('W', 'f'), ('Scale', 'f'), ('Smoothness', 'f'), ('Exponent', 'f'),
                 ('Randomness', 'f')],
                [('Distance', 'f'), ('Color', 'v'), ('Position', 'v'), ('W', 'f'), ('Radius', 'f')]),
    'musgrave': ('ShaderNodeTexMusgrave', 'kOpTexMusgrave',
                 [('Vector', 'v'), ('W', 'f'), ('Scale', 'f'), ('Detail', 'f'), ('Dimension', 'f'),
                  ('Lacunarity', 'f'), ('Offset', 'f'), ('Gain', 'f')], [('Fac', 'f')]),
    'wave': ('ShaderNodeTexWave', 'kOpTexWave',
             [('Vector', 'v'), ('Scale', 'f'), ('Distortion', 'f'), ('Detail', 'f'), ('Detail Scale', 'f'),
              ('Detail Roughness', 'f'), ('Phase Offset', 'f')], [('Color', 'v'), ('Fac', 'f')]),
    'magic': ('ShaderNodeTexMagic', 'kOpTexMagic', [('Vector', 'v'), ('Scale', 'f'), ('Distortion', 'f')],
              [('Color', 'v'), ('Fac', 'f')]),
    'checker': ('ShaderNodeTexChecker', 'kOpTexChecker',
                [('Vector', 'v'), ('Color1', 'v'), ('Color2', 'v'), ('Scale', 'f')], [('Color', 'v'), ('Fac', 'f')]),
    'brick': ('ShaderNodeTexBrick', 'kOpTexBrick',
              [('Vector', 'v'), ('Color1', 'v'), ('Color2', 'v'), ('Mortar', 'v'), ('Scale', 'f'),
               ('Mortar Size', 'f'), ('Mortar Smooth', 'f'), ('Bias', 'f'), ('Brick Width', 'f'),
               ('Row Height', 'f')], [('Color', 'v'), ('Fac', 'f')]),
    'gradient': ('ShaderNodeTexGradient', 'kOpTexGradient', [('Vector', 'v')], [('Color', 'v'), ('Fac', 'f')]),
    'white': ('ShaderNodeTexWhiteNoise', 'kOpTexWhiteNoise', [('Vector', 'v'), ('W', 'f')],
              [('Value', 'f'), ('Color', 'v')]),
}

DIMS = {'1D': 1, '2D': 2, '3D': 3, '4D': 4}
VOR_FEATURE = {'F1': 0, 'F2': 1, 'SMOOTH_F1': 2, 'DISTANCE_TO_EDGE': 3, 'N_SPHERE_RADIUS': 4}
VOR_METRIC = {'EUCLIDEAN': 0, 'MANHATTAN': 1, 'CHEBYCHEV': 2, 'MINKOWSKI': 3}
MUSGRAVE = {'MULTIFRACTAL': 0, 'FBM': 1, 'HYBRID_MULTIFRACTAL': 2, 'RIDGED_MULTIFRACTAL': 3, 'HETERO_TERRAIN': 4}
WAVE = {'BANDS': 0, 'RINGS': 1}
BANDS = {'X': 0, 'Y': 1, 'Z': 2, 'DIAGONAL': 3}
RINGS = {'X': 0, 'Y': 1, 'Z': 2, 'SPHERICAL': 3}
PROFILE = {'SIN': 0, 'SAW': 1, 'TRI': 2}
GRADIENT = {'LINEAR': 0, 'QUADRATIC': 1, 'EASING': 2, 'DIAGONAL': 3, 'RADIAL': 4, 'QUADRATIC_SPHERE': 5,
            'SPHERICAL': 6}


def fbits(x):
    return struct.unpack('<I', struct.pack('<f', x))[0]


def params(kind, props):
    if kind == 'noise' or kind == 'white':
        return [DIMS[props['noise_dimensions']]]
    if kind == 'voronoi':
        return [DIMS[props['voronoi_dimensions']], VOR_FEATURE[props['feature']], VOR_METRIC[props['distance']]]
    if kind == 'musgrave':
        return [DIMS[props['musgrave_dimensions']], MUSGRAVE[props['musgrave_type']]]
    if kind == 'wave':
        return [WAVE[props['wave_type']], BANDS[props['bands_direction']], RINGS[props['rings_direction']],
                PROFILE[props['wave_profile']]]
    if kind == 'magic':
        return [props['turbulence_depth']]
    if kind == 'brick':
        return [props['offset_frequency'], props['squash_frequency'], fbits(props['offset']), fbits(props['squash'])]
    if kind == 'gradient':
        return [GRADIENT[props['gradient_type']]]
    return []


P1 = (0.37, -1.21, 2.53)
P2 = (4.71, 3.18, -0.62)
P3 = (-7.3, 0.45, 12.9)

CASES = []
for d in ('1D', '2D', '3D', '4D'):
    for p in (P1, P2):
        CASES.append(('noise', {'noise_dimensions': d},
                      {'Vector': p, 'W': 0.71, 'Scale': 2.3, 'Detail': 3.5, 'Roughness': 0.6, 'Distortion': 0.0}))
    CASES.append(('noise', {'noise_dimensions': d},
                  {'Vector': P3, 'W': -1.9, 'Scale': 0.8, 'Detail': 2.0, 'Roughness': 0.45, 'Distortion': 1.7}))
for d in ('1D', '2D', '3D', '4D'):
    for f in VOR_FEATURE:
        metrics = ['EUCLIDEAN'] if f in ('DISTANCE_TO_EDGE', 'N_SPHERE_RADIUS') else list(VOR_METRIC)
        for m in metrics:
            CASES.append(('voronoi', {'voronoi_dimensions': d, 'feature': f, 'distance': m},
                          {'Vector': P2, 'W': 1.37, 'Scale': 1.9, 'Smoothness': 0.7, 'Exponent': 1.6,
                           'Randomness': 0.85}))
for d in ('1D', '2D', '3D', '4D'):
    for t in MUSGRAVE:
        CASES.append(('musgrave', {'musgrave_dimensions': d, 'musgrave_type': t},
                      {'Vector': P1, 'W': 0.33, 'Scale': 1.7, 'Detail': 4.4, 'Dimension': 1.3, 'Lacunarity': 2.1,
                       'Offset': 0.9, 'Gain': 1.2}))
for t in ('BANDS', 'RINGS'):
    for dr in ('X', 'Y', 'Z', 'DIAGONAL' if t == 'BANDS' else 'SPHERICAL'):
        for pr in PROFILE:
            props = {'wave_type': t, 'bands_direction': dr if t == 'BANDS' else 'X',
                     'rings_direction': dr if t == 'RINGS' else 'X', 'wave_profile': pr}
            CASES.append(('wave', props, {'Vector': P1, 'Scale': 0.9, 'Distortion': 2.5 if pr == 'SIN' else 0.0,
                                          'Detail': 2.5, 'Detail Scale': 1.3, 'Detail Roughness': 0.55,
                                          'Phase Offset': 0.4}))
for depth in (0, 1, 2, 4, 7, 10):
    CASES.append(('magic', {'turbulence_depth': depth}, {'Vector': P2, 'Scale': 1.3, 'Distortion': 1.8}))
for p in (P1, P2, P3):
    CASES.append(('checker', {}, {'Vector': p, 'Color1': (0.9, 0.2, 0.1), 'Color2': (0.1, 0.3, 0.8), 'Scale': 3.1}))
for p in (P1, P2, P3, (0.51, 0.13, 0.0), (0.02, 0.98, 0.0)):
    for of, sf, o, s in ((2, 2, 0.5, 1.0), (3, 2, 0.3, 0.6)):
        CASES.append(('brick', {'offset_frequency': of, 'squash_frequency': sf, 'offset': o, 'squash': s},
                      {'Vector': p, 'Color1': (0.8, 0.3, 0.1), 'Color2': (0.2, 0.6, 0.3), 'Mortar': (0.1, 0.1, 0.1),
                       'Scale': 5.0, 'Mortar Size': 0.05, 'Mortar Smooth': 0.4, 'Bias': 0.1, 'Brick Width': 0.5,
                       'Row Height': 0.25}))
for t in GRADIENT:
    for p in ((0.37, 0.21, 0.1), (-0.4, 0.5, 0.2)):
        CASES.append(('gradient', {'gradient_type': t}, {'Vector': p}))
for d in ('1D', '2D', '3D', '4D'):
    for p in (P1, P3):
        CASES.append(('white', {'noise_dimensions': d}, {'Vector': p, 'W': 0.77}))


def setup_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
    scene.render.resolution_x = scene.render.resolution_y = 4
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.view_settings.view_transform = 'Standard'
    bpy.ops.mesh.primitive_plane_add(size=10)
    plane = bpy.context.object
    cam = bpy.data.cameras.new('cam')
    cam.type = 'ORTHO'
    cam.ortho_scale = 2
    cam_ob = bpy.data.objects.new('cam', cam)
    cam_ob.location = (0, 0, 5)
    scene.collection.objects.link(cam_ob)
    scene.camera = cam_ob
    mat = bpy.data.materials.new('tex')
    mat.use_nodes = True
    plane.data.materials.append(mat)
    return scene, mat


def render_value(scene, mat, kind, props, values, output, size):
    # Linked emission passes negative values (only a constant black or negative colour is dropped);
    # the negated render checks that.
    pos = render_part(scene, mat, kind, props, values, output, size, 1.0)
    neg = render_part(scene, mat, kind, props, values, output, size, -1.0)
    if any(abs(p + n) > 1e-6 * max(1.0, abs(p)) for p, n in zip(pos, neg)):
        sys.exit('negated render of %s %s is not the negative: %s %s' % (kind, props, pos, neg))
    return pos


def make_node(nt, kind, props):
    node = nt.nodes.new(NODES[kind][0])
    for k, v in props.items():
        setattr(node, k, v)
    return node


def render_part(scene, mat, kind, props, values, output, size, sign):
    nt = mat.node_tree
    nt.nodes.clear()
    node = make_node(nt, kind, props)
    for name, value in values.items():
        sock = node.inputs[name]
        if name == 'Vector':
            xyz = nt.nodes.new('ShaderNodeCombineXYZ')
            for i in range(3):
                xyz.inputs[i].default_value = value[i]
            nt.links.new(xyz.outputs[0], sock)
        elif isinstance(value, tuple):
            sock.default_value = (*value, 1.0)
        else:
            sock.default_value = value
    em = nt.nodes.new('ShaderNodeEmission')
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    if sign > 0:
        nt.links.new(node.outputs[output], em.inputs['Color'])
    elif size == 'v':
        neg = nt.nodes.new('ShaderNodeVectorMath')
        neg.operation = 'SCALE'
        neg.inputs['Scale'].default_value = -1.0
        nt.links.new(node.outputs[output], neg.inputs[0])
        nt.links.new(neg.outputs[0], em.inputs['Color'])
    else:
        neg = nt.nodes.new('ShaderNodeMath')
        neg.operation = 'MULTIPLY'
        neg.inputs[1].default_value = -1.0
        nt.links.new(node.outputs[output], neg.inputs[0])
        nt.links.new(neg.outputs[0], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    path = os.path.join(tempfile.gettempdir(), 'lantern_texref.exr')
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    px = list(img.pixels[0:3])
    bpy.data.images.remove(img)
    return px


def fmt(x):
    if x != x:
        return 'NAN'
    if isinstance(x, int):
        return '%du' % x
    s = '%.9g' % x
    return s + ('f' if ('.' in s or 'e' in s) else '.0f')


def main():
    scene, mat = setup_scene()
    # Emission must pass large values unchanged.
    for probe in (0.25, 3.5):
        nt = mat.node_tree
        nt.nodes.clear()
        em = nt.nodes.new('ShaderNodeEmission')
        em.inputs['Color'].default_value = (probe, probe, probe, 1)
        out = nt.nodes.new('ShaderNodeOutputMaterial')
        nt.links.new(em.outputs[0], out.inputs['Surface'])
        scene.render.filepath = os.path.join(tempfile.gettempdir(), 'lantern_texref.exr')
        bpy.ops.render.render(write_still=True)
        img = bpy.data.images.load(scene.render.filepath)
        got = img.pixels[0]
        bpy.data.images.remove(img)
        if abs(got - probe) > 1e-6:
            sys.exit('emission does not pass %g through (got %g)' % (probe, got))
    lines = []
    for kind, props, values in CASES:
        _, op, ins, outs = NODES[kind]
        flat_in = []
        for name, size in ins:
            v = values.get(name, (0.0, 0.0, 0.0) if size == 'v' else 0.0)
            flat_in += list(v) if size == 'v' else [v]
        flat_out = []
        nt = mat.node_tree
        nt.nodes.clear()
        probe = make_node(nt, kind, props)
        enabled = {name: probe.outputs[name].enabled for name, _ in outs}
        for name, size in outs:
            # An output the mode hides cannot be linked in Blender: no reference (NAN, skipped).
            if not enabled[name]:
                flat_out += [float('nan')] * (3 if size == 'v' else 1)
                continue
            px = render_value(scene, mat, kind, props, values, name, size)
            flat_out += px if size == 'v' else [px[0]]
        label = kind + ' ' + ' '.join(str(v) for v in props.values())
        lines.append('    {lt::%s, {%s}, {%s}, {%s}, "%s"},' % (
            op, ', '.join(fmt(p) for p in params(kind, props)), ', '.join(fmt(float(x)) for x in flat_in),
            ', '.join(fmt(float(x)) for x in flat_out), label))
    with open(OUT, 'w') as f:
        f.write('// Generated by scripts/cycles_texture_reference.py from Cycles renders (Blender %s): each row\n'
                '// is one texture instruction (opcode, params, inputs and outputs flattened in instruction order).\n'
                '#pragma once\n\n#include <cmath>\n#include <cstdint>\n\n#include "shading/textures.h"\n\n'
                'namespace cycles_ref {\n\nstruct TextureCase {\n  uint32_t op;\n  uint32_t params[4];\n'
                '  float in[24];\n  float out[12];\n  const char* label;\n};\n\n'
                'inline const TextureCase kTextureCases[] = {\n' % bpy.app.version_string)
        f.write('\n'.join(lines) + '\n};\n\n}  // namespace cycles_ref\n')
    print('wrote %d cases to %s' % (len(lines), OUT))


main()
