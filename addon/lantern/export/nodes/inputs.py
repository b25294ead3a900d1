"""Nodes that read the shading point, constants and image textures (inputs.h in the core)."""

from . import TEX_COORD_OUTPUTS, ops, register
from .attributes import default_uv, registry
from .textures import float_bits

MAGENTA = (1.0, 0.0, 1.0)  # a missing image, as Cycles renders it


@register('VALUE')
def value(c, node, want):
    return {node.outputs[0].name: c.const(float(node.outputs[0].default_value))}


@register('RGB')
def rgb(c, node, want):
    return {node.outputs[0].name: c.const(tuple(node.outputs[0].default_value)[:3])}


@register('TEX_COORD')
def tex_coord(c, node, want):
    if want.name in ("Camera", "Window") and c.camera is None:
        c.warn("Texture Coordinate '%s': %s output needs the scene camera; 0 is used" % (node.name, want.name))
    table = ()
    if node.object is not None and want.name == "Object":
        # Another object's space: its world-to-object matrix as a table.
        m = node.object.matrix_world.inverted()
        table = [m[r][k] for r in range(3) for k in range(4)]
    if node.outputs["UV"].is_linked:
        default_uv(c)
    return {n: c.texcoord(n, table) for n in TEX_COORD_OUTPUTS}


@register('NEW_GEOMETRY')
def geometry(c, node, want):
    if want.name in ("Pointiness", "Random Per Island"):
        c.warn("Geometry '%s': %s is not computed (0.5 and 0 are used)" % (node.name, want.name))
    return c.geometry()


@register('BUMP')
def bump(c, node, want):
    """Cycles' bump: the Height input at the point and moved by the ray footprint's two
    differentials in the surface (the input's nodes compiled three times)."""
    heights = c.heights(node.inputs["Height"])
    return c.emit(ops.BUMP, [c.float(node.inputs["Strength"]), c.float(node.inputs["Distance"])] + heights +
                  [c.normal(node.inputs["Normal"])], [("Normal", 3)], params=[int(node.invert)])


@register('WIREFRAME')
def wireframe(c, node, want):
    """Cycles' Wireframe: the shading point's triangle edges (as the renderer triangulates)."""
    return c.emit(ops.WIREFRAME, [c.float(node.inputs["Size"])], [("Fac", 1)],
                  params=[int(node.use_pixel_size), c.bump])


@register('AMBIENT_OCCLUSION')
def ambient_occlusion(c, node, want):
    """Cycles' Ambient Occlusion: an unlinked Distance of 0 means the World's AO distance (Cycles'
    NODE_AO_GLOBAL_RADIUS)."""
    dist = node.inputs["Distance"]
    distance = c.const(c.ao_distance) if not c.linked(dist) and dist.default_value == 0 else c.float(dist)
    return c.emit(ops.AMBIENT_OCCLUSION, [c.color(node.inputs["Color"]), distance, c.normal(node.inputs["Normal"])],
                  [("Color", 3), ("AO", 1)], params=[max(1, min(int(node.samples), 128)),
                                                     int(node.only_local) | 2 * int(node.inside)])


@register('BEVEL')
def bevel(c, node, want):
    """Cycles' Bevel: the normals of the object's surface within Radius, from Samples rays at the
    path's vertices (light samples and shadow rays see the shading normal, as in Cycles)."""
    return c.emit(ops.BEVEL, [c.float(node.inputs["Radius"]), c.normal(node.inputs["Normal"])], [("Normal", 3)],
                  params=[max(1, min(int(node.samples), 128))])


@register('CAMERA')
def camera_data(c, node, want):
    if c.camera is None:
        c.warn("Camera Data '%s' needs the scene camera; 0 is used" % node.name)
    return c.emit(ops.CAMERA_DATA, [], [("View Vector", 3), ("View Z Depth", 1), ("View Distance", 1)],
                  params=[c.table(c.camera or [])])


@register('LIGHT_FALLOFF')
def light_falloff(c, node, want):
    return c.emit(ops.LIGHT_FALLOFF, [c.float(node.inputs["Strength"]), c.float(node.inputs["Smooth"])],
                  [("Quadratic", 1), ("Linear", 1), ("Constant", 1)])


@register('FRESNEL')
def fresnel(c, node, want):
    return c.emit(ops.FRESNEL, [c.float(node.inputs["IOR"]), c.normal(node.inputs["Normal"])], [("Fac", 1)])


@register('LAYER_WEIGHT')
def layer_weight(c, node, want):
    return c.emit(ops.LAYER_WEIGHT, [c.float(node.inputs["Blend"]), c.normal(node.inputs["Normal"])],
                  [("Fresnel", 1), ("Facing", 1)])


_LIGHT_PATH = ("Is Camera Ray", "Is Shadow Ray", "Is Diffuse Ray", "Is Glossy Ray", "Is Singular Ray",
               "Is Reflection Ray", "Is Transmission Ray", "Is Volume Scatter Ray", "Ray Length",
               "Ray Depth", "Diffuse Depth", "Glossy Depth", "Transparent Depth", "Transmission Depth")


@register('LIGHT_PATH')
def light_path(c, node, want):
    if want.name in ("Is Shadow Ray", "Is Singular Ray", "Is Volume Scatter Ray"):
        c.warn("Light Path '%s': %s is always 0 in Lantern" % (node.name, want.name))
    return c.emit(ops.LIGHT_PATH, [], [(n, 1) for n in _LIGHT_PATH])


_PROJECTIONS = {'BOX': 0, 'SPHERE': 1, 'TUBE': 2}  # Flat: kOpImage


@register('TEX_IMAGE')
def image_texture(c, node, want):
    where = "%s, image texture '%s'" % (c.subject, node.name)
    image_id = c.images.export(node.image, node.interpolation, node.extension, where, alpha=True) \
        if node.image is not None else None
    if image_id is None:
        if node.image is None:
            c.warn("image texture '%s' has no image; it renders magenta (as Cycles)" % node.name)
        return {"Color": c.const(MAGENTA), "Alpha": c.const(1.0)}
    sock = node.inputs["Vector"]
    vec = c.vector(sock) if c.linked(sock) else default_uv(c)
    # Cycles divides colours by alpha where the Alpha output reaches the shader output
    # (NODE_IMAGE_ALPHA_UNASSOCIATE): the param is set when something reads Alpha (Compiler.read).
    if node.projection in _PROJECTIONS:
        blend = float_bits(max(0.0, min(1.0, node.projection_blend)))
        outputs = c.emit(ops.IMAGE_PROJECTED, [vec], [("Color", 3), ("Alpha", 1)],
                         params=[image_id, 0, _PROJECTIONS[node.projection], blend])
        c.on_read(outputs["Alpha"], len(c.code) - 3)
        return outputs
    outputs = c.emit(ops.IMAGE, [vec], [("Color", 3), ("Alpha", 1)], params=[image_id, 0])
    c.on_read(outputs["Alpha"], len(c.code) - 1)
    return outputs


_SPACES = {'WORLD': 0, 'OBJECT': 1, 'CAMERA': 2}
_VECTOR_TYPES = {'POINT': 0, 'VECTOR': 1, 'NORMAL': 2}


@register('VECT_TRANSFORM')
def vector_transform(c, node, want):
    table = []
    if c.camera is not None:
        import mathutils
        rows = [c.camera[4 * r:4 * r + 4] for r in range(3)]
        to_camera = mathutils.Matrix(rows + [(0.0, 0.0, 0.0, 1.0)])
        to_world = to_camera.inverted_safe()
        table = [v for r in rows for v in r] + [to_world[r][k] for r in range(3) for k in range(4)]
    elif 'CAMERA' in (node.convert_from, node.convert_to) and node.convert_from != node.convert_to:
        c.warn("Vector Transform '%s': camera space needs the scene camera; world space is used" % node.name)
    return c.emit(ops.VECTOR_TRANSFORM, [c.vector(node.inputs["Vector"])], [("Vector", 3)],
                  params=[_VECTOR_TYPES[node.vector_type], _SPACES[node.convert_from], _SPACES[node.convert_to],
                          c.table(table)])


@register('DISPLACEMENT')
def displacement(c, node, want):
    ins = [c.float(node.inputs[n]) for n in ("Height", "Midlevel", "Scale")] + [c.normal(node.inputs["Normal"])]
    return c.emit(ops.DISPLACEMENT, ins, [("Displacement", 3)], params=[int(node.space == 'WORLD')])


@register('VECTOR_DISPLACEMENT')
def vector_displacement(c, node, want):
    space = {'TANGENT': 0, 'OBJECT': 1, 'WORLD': 2}[node.space]
    # Cycles reads the active render UV map's tangent in tangent space.
    tid = registry(c).id('tangent', '') if space == 0 else 0
    ins = [c.vector(node.inputs["Vector"]), c.float(node.inputs["Midlevel"]), c.float(node.inputs["Scale"])]
    return c.emit(ops.VECTOR_DISPLACEMENT, ins, [("Displacement", 3)], params=[space, tid])


_ENV_PROJECTIONS = {'EQUIRECTANGULAR': 0, 'MIRROR_BALL': 1}


@register('TEX_ENVIRONMENT')
def environment_texture(c, node, want):
    """Cycles' svm_node_tex_environment: the image seen along the (normalised) Vector, by default
    the Position (in a world, the direction of the ray)."""
    where = "%s, environment texture '%s'" % (c.subject, node.name)
    projection = _ENV_PROJECTIONS.get(node.projection)
    if projection is None:
        c.warn("environment texture '%s': %s projection is not supported; Equirectangular is used"
               % (node.name, node.projection))
        projection = 0
    # Cycles gives environment images no extension setting: they repeat.
    image_id = c.images.export(node.image, node.interpolation, getattr(node, "extension", 'REPEAT'), where,
                               alpha=True) if node.image is not None else None
    if image_id is None:
        if node.image is None:
            c.warn("environment texture '%s' has no image; it renders magenta (as Cycles)" % node.name)
        return {"Color": c.const(MAGENTA), "Alpha": c.const(1.0)}
    vec = c.vector(node.inputs["Vector"], default=c.geometry()["Position"])
    outputs = c.emit(ops.ENVIRONMENT, [vec], [("Color", 3), ("Alpha", 1)], params=[image_id, 0, projection])
    c.on_read(outputs["Alpha"], len(c.code) - 2)
    return outputs


@register('HAIR_INFO')
def hair_info(c, node, want):
    return c.emit(ops.HAIR_INFO, [], [("Is Strand", 1), ("Intercept", 1), ("Length", 1), ("Thickness", 1),
                                      ("Tangent Normal", 3), ("Random", 1)])


@register('POINT_INFO')
def point_info(c, node, want):
    return c.emit(ops.POINT_INFO, [], [("Position", 3), ("Radius", 1), ("Random", 1)])
