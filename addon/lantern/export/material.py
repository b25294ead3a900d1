"""Material export: a material's surface node tree compiled into a shader program (nodes/), its
Volume output into homogeneous medium components, and the images textures use."""

import os

import bpy

from .. import core
from . import nodes
from .cryptomatte import Names
from .mesh import view_layer_value
from .names import core_call, is_finite
from .nodes.attributes import AttributeRegistry

# Rec. 709 luma, as Blender converts a colour into a float socket.
_LUMA = (0.2126, 0.7152, 0.0722)

# Smart is Cubic on the CPU (Cycles' kernel/device/cpu/image.h).
_INTERPOLATION = {'Linear': core.INTERP_LINEAR, 'Closest': core.INTERP_CLOSEST, 'Cubic': core.INTERP_CUBIC,
                  'Smart': core.INTERP_CUBIC}
_EXTENSION = {'REPEAT': core.EXTENSION_REPEAT, 'EXTEND': core.EXTENSION_EXTEND,
              'CLIP': core.EXTENSION_CLIP}


class ImageExporter:
    """Exports each (image, colour space, interpolation, extension) once; returns core ids.

    Images whose file the core can read itself (image_file below) are read by the core from that
    file, as Cycles reads them: Blender never loads their pixels and the core holds them once, at
    the file's precision. Every other image (packed, generated, edited in memory, movies,
    sequences, UDIMs, formats or colour spaces the core leaves to Blender) goes through
    Image.pixels into the core's own buffer. Both give the same texels."""

    def __init__(self, core_scene, report):
        self.core_scene = core_scene
        self.report = report
        self.ids = {}
        self.from_files = 0  # images the core read from their files

    def export(self, image, interpolation='Linear', extension='REPEAT', where="", alpha=False):
        """Core image id, or None (reported) when the image cannot be used. alpha: keep the image's
        alpha as Cycles reads it (image textures), else drop it."""
        if image is None:
            self.report({'WARNING'}, "%s: image texture without an image" % where)
            return None
        key = (image.original.as_pointer(), interpolation, extension, alpha)
        if key in self.ids:
            return self.ids[key]
        interp = _INTERPOLATION.get(interpolation)
        if interp is None:
            self.report({'WARNING'}, "%s: %s interpolation is not supported, treated as Linear"
                                     % (where, interpolation))
            interp = core.INTERP_LINEAR
        ext = _EXTENSION.get(extension)
        if ext is None:
            self.report({'WARNING'}, "%s: %s extension is not supported, treated as Repeat"
                                     % (where, extension))
            ext = core.EXTENSION_REPEAT
        space = image.colorspace_settings.name
        path = image_file(image)
        if path is not None:
            other = _color_space(image) == "OTHER"
            try:
                image_id = self.core_scene.add_image_file(
                    path, _color_space(image), _ALPHA_MODES.get(image.alpha_mode, "STRAIGHT"),
                    use_alpha=alpha, interpolation=interp, extension=ext,
                    ocio=(ocio_config(), space) if other else None)
            except core.LanternError as e:  # left to Blender (the reason is printed)
                print("Lantern: image '%s' is loaded through Blender: %s" % (image.name, e.detail))
            else:
                self.ids[key] = image_id
                self.from_files += 1
                return image_id
        if image.source == 'TILED':
            self.report({'WARNING'}, "%s: image '%s' is a UDIM (tiled) image, only its first tile "
                                     "is used" % (where, image.name))
        width, height = image.size[:]  # loads the image if needed
        channels = image.channels
        if width <= 0 or height <= 0 or channels not in (1, 3, 4):
            self.report({'WARNING'}, "%s: image '%s' has no pixels (missing file?); it renders "
                                     "magenta (as Cycles)" % (where, image.name))
            self.ids[key] = None
            return None
        # Byte images give their stored values: sRGB-encoded when the colour space is sRGB, the
        # core converts other spaces (OpenColorIO, as Cycles converts them). Float images are
        # already linear; Non-Color data is raw.
        srgb = (not image.is_float) and space == 'sRGB'
        other = not image.is_float and _color_space(image) == "OTHER"
        # Blender's pixels go straight into the core's buffer (one copy); the core keeps byte
        # images at 8 bits (their values are exactly b / 255), and alpha where it is not 1.
        try:
            image_id = self.core_scene.add_image_filled(
                image.pixels.foreach_get, width, height, channels, srgb=srgb, interpolation=interp,
                extension=ext, alpha=_alpha_mode(image) if alpha else core.ALPHA_IGNORE,
                ocio=(ocio_config(), space) if other else None)
        except core.LanternError as e:  # a colour space OpenColorIO cannot convert
            self.report({'WARNING'}, "%s: image '%s': %s; it renders magenta (as Cycles)"
                                     % (where, image.name, e.detail))
            self.ids[key] = None
            return None
        self.ids[key] = image_id
        return image_id


def ocio_config():
    """The OpenColorIO configuration Blender and Cycles use (Blender's colormanagement_init): the
    OCIO environment variable's file, else Blender's own."""
    env = os.environ.get("OCIO")
    if env and os.path.isfile(env):
        return env
    return os.path.join(bpy.utils.system_resource('DATAFILES'), "colormanagement", "config.ocio")


# Blender's Image.alpha_mode as lt_alpha_mode names.
_ALPHA_MODES = {'STRAIGHT': "STRAIGHT", 'PREMUL': "PREMULTIPLIED", 'CHANNEL_PACKED': "CHANNEL_PACKED",
                'NONE': "NONE"}


def image_file(image):
    """The file the core may read an image from (absolute path), or None when the pixels must come
    from Blender: packed, generated or viewer images, movies, sequences and UDIMs, images edited in
    memory (dirty), and missing files (Blender's path then reports them). Reads nothing that
    would make Blender load the pixels."""
    if image.source != 'FILE' or image.packed_file is not None or len(image.packed_files) \
            or image.is_dirty or image.use_multiview:
        return None
    path = bpy.path.abspath(image.filepath, library=image.library)
    return path if os.path.isfile(path) else None


def _color_space(image):
    """The image's colour space as an lt_color_space name."""
    settings = image.colorspace_settings
    if settings.is_data:
        return "DATA"
    return {"sRGB": "SRGB", "Linear": "LINEAR"}.get(settings.name, "OTHER")


def _alpha_mode(image):
    """How Cycles 3.4 reads an image's alpha from Blender (measured against it, tests/blender/
    test_nodes_inputs.py): byte images are straight whatever their alpha mode (Blender keeps byte
    buffers straight) and Cycles associates them; float images are kept premultiplied (Blender's
    float buffers are); data (Non-Color) and channel-packed images keep colours apart from alpha."""
    if image.alpha_mode == 'NONE':
        return core.ALPHA_IGNORE
    if image.alpha_mode == 'CHANNEL_PACKED' or image.colorspace_settings.is_data:
        return core.ALPHA_CHANNEL_PACKED
    return core.ALPHA_PREMULTIPLIED if image.is_float else core.ALPHA_STRAIGHT


def follow(socket):
    """The output socket feeding an input socket through reroutes and muted nodes, or None."""
    seen = 0
    while socket is not None and seen < 256:
        seen += 1
        links = [l for l in socket.links if l.is_valid and not l.is_muted]
        if not links:
            return None
        out = links[0].from_socket
        node = out.node
        if node.type == 'REROUTE':
            socket = node.inputs[0]
            continue
        if node.mute:
            # A muted node passes its internal link's input through, or gives nothing.
            socket = next((l.from_socket for l in node.internal_links if l.to_socket == out), None)
            continue
        return out
    return None


_VOLUME_KINDS = {'PRINCIPLED_VOLUME': core.VOLUME_PRINCIPLED, 'VOLUME_SCATTER': core.VOLUME_SCATTER,
                 'VOLUME_ABSORPTION': core.VOLUME_ABSORPTION, 'EMISSION': core.VOLUME_EMISSION}
_VOLUME_INPUTS = ("Color", "Density", "Anisotropy", "Absorption Color", "Emission Strength",
                  "Emission Color", "Blackbody Intensity", "Blackbody Tint", "Temperature", "Strength")


def _constant_value(socket, warn, where):
    """A socket's value when unlinked or linked from an RGB / Value node; otherwise the socket's
    own value, reported."""
    out = follow(socket)
    if out is None:
        return socket.default_value
    if out.node.type in {'RGB', 'VALUE'}:
        v = out.default_value
        if isinstance(socket.default_value, float) and not isinstance(v, float):
            return _convert(tuple(v), False)
        if not isinstance(socket.default_value, float) and isinstance(v, float):
            return (v, v, v, 1.0)
        return v
    warn("'%s' of %s is linked from '%s' (%s); only constant volume inputs are supported, the "
         "socket's value is used" % (socket.name, where, out.node.name, out.node.bl_idname))
    return socket.default_value


def volume_keywords(output, warn, attributes=False):
    """The Volume input of an output node (Material Output or World Output) as the list of
    components set_material_volume / set_world_volume / add_volume_grid take, [] when a Volume
    input is linked but nothing in it can be used (reported), or None without a Volume input.

    Add Shader sums its inputs and Mix Shader weights them by (1 - fac, fac), as Cycles mixes
    closures: the weight scales a component's Density (and an Emission node's Strength). Cycles
    3.4's Principled Volume does not scale its own emission by the mix weight (svm_closure.h), and
    neither does this. Unsupported nodes are reported and left out.

    attributes (Volume objects): an Attribute node (Fac, geometry attribute) feeding Density,
    Emission Strength / Strength, Blackbody Intensity or Temperature reads the grid of its name,
    as Cycles reads the object's volume attributes: the socket's value becomes 1 (times the mix
    weight) and the component names the grid (core's emission_strength_grid, ...; the density
    grid is export/volume.py's); Principled Volume's Temperature Attribute and Color Attribute are
    kept as temperature_attribute and color_attribute."""
    if output is None or "Volume" not in output.inputs:
        return None
    if follow(output.inputs["Volume"]) is None:
        return None
    components = []
    seen = set()

    def walk(socket, weight, depth):
        out = follow(socket)
        if out is None or weight <= 0.0 or depth > 64:
            return
        node = out.node
        if node.type == 'ADD_SHADER':
            walk(node.inputs[0], weight, depth + 1)
            walk(node.inputs[1], weight, depth + 1)
            return
        if node.type == 'MIX_SHADER':
            fac = _constant_value(node.inputs[0], warn, "mix shader '%s'" % node.name)
            fac = min(1.0, max(0.0, float(fac)))
            walk(node.inputs[1], weight * (1.0 - fac), depth + 1)
            walk(node.inputs[2], weight * fac, depth + 1)
            return
        if node.type not in _VOLUME_KINDS:
            if node.name not in seen:
                seen.add(node.name)
                warn("volume node '%s' (%s) is not supported (Principled Volume, Volume Scatter, "
                     "Volume Absorption, Emission, Add Shader and Mix Shader are); it is left out"
                     % (node.name, node.bl_idname))
            return
        where = "volume '%s'" % node.name

        grids = {}

        def value(name, default, grid_key=None):
            s = node.inputs.get(name)
            if s is None:
                return default
            src = follow(s) if attributes and grid_key else None
            if src is not None and src.node.type == 'ATTRIBUTE' and src.name == "Fac" \
                    and src.node.attribute_type == 'GEOMETRY' and src.node.attribute_name:
                if grid_key != "density":  # the density grid is export/volume.py's
                    grids[grid_key] = src.node.attribute_name
                return 1.0
            return _constant_value(s, warn, where)

        kind = _VOLUME_KINDS[node.type]
        if kind == core.VOLUME_EMISSION:
            strength = float(value("Strength", 1.0, "emission_strength_grid")) * weight
            components.append(dict(node=kind, name=node.name, density=0.0, emission_strength=strength,
                                   emission_color=tuple(value("Color", (1.0, 1.0, 1.0)))[:3], **grids))
            return
        c = dict(node=kind, name=node.name, color=tuple(value("Color", (1.0, 1.0, 1.0)))[:3],
                 density=float(value("Density", 1.0, "density")) * weight,
                 absorption_color=tuple(value("Absorption Color", (0.0, 0.0, 0.0)))[:3],
                 anisotropy=float(value("Anisotropy", 0.0)))
        if kind == core.VOLUME_PRINCIPLED:
            c.update(emission_strength=float(value("Emission Strength", 0.0, "emission_strength_grid")),
                     emission_color=tuple(value("Emission Color", (1.0, 1.0, 1.0)))[:3],
                     blackbody_intensity=float(value("Blackbody Intensity", 0.0, "blackbody_intensity_grid")),
                     blackbody_tint=tuple(value("Blackbody Tint", (1.0, 1.0, 1.0)))[:3],
                     temperature=float(value("Temperature", 1000.0, "temperature_grid")))
            if attributes:
                for key, socket in (("temperature_attribute", "Temperature Attribute"),
                                    ("color_attribute", "Color Attribute")):
                    name = node.inputs[socket].default_value if socket in node.inputs else ""
                    if name:
                        grids[key] = name
        c.update(grids)
        components.append(c)

    walk(output.inputs["Volume"], 1.0, 0)
    return components


def emissive_nodes(components):
    """Names of the nodes among `components` that emit (volume emission)."""
    return [c.get("name", "?") for c in components or ()
            if c.get("emission_strength", 0.0) > 0.0 or c.get("blackbody_intensity", 0.0) > 0.0]


# Cycles' displacement methods that move vertices -> lt_displacement_method.
_DISPLACEMENT_METHODS = {'DISPLACEMENT': core.DISPLACEMENT_TRUE, 'BOTH': core.DISPLACEMENT_BOTH}


def _program_key(displaced):
    """A comparable form of (program, method) or None."""
    if displaced is None:
        return None
    (code, constants, registers), method = displaced
    return tuple(code), tuple(float(k) for k in constants), registers, method


class MaterialExporter:
    """Translates each material once; `export(material)` returns its core id."""

    def __init__(self, core_scene, report, images):
        self.camera = None  # Texture Coordinate's camera table (camera.camera_table)
        self.ao_distance = 10.0  # the World's AO distance (Ambient Occlusion's Distance 0)
        self.aovs = {}  # AOV name -> (index, colour) of the view layer's valid AOVs (aov_indices)
        # The depsgraph View Layer attributes are read from (each render's, each viewport update's),
        # and the values the translated programs hold (a viewport update compares them anew).
        self.depsgraph = None
        self.view_layer_seen = {}
        self.core_scene = core_scene
        self.report = report
        self.images = images
        self.ids = {}
        self.volumes = {}  # material key -> (volume keywords or None, null surface) as exported
        self.displacements = {}  # material key -> its true displacement as exported (_program_key)
        self._displaced = None
        self.volume_names = {}  # core id -> name, of the materials with a medium
        self.media = 0  # materials with a Volume output
        self.emissive_media = 0  # of those, volumes that emit
        self.subsurface = set()  # names of the materials that scatter under their surface
        self.attributes = AttributeRegistry()  # names the programs read (export/mesh.py exports them)
        self.geometry_reads = {}  # core material id -> the geometry values its program reads (registry keys)
        self.cryptomatte = Names()  # the Cryptomatte names of materials and (export/mesh.py) objects

    # -- public --------------------------------------------------------------------------------

    def export(self, material):
        if material is None:
            return -1
        key = material.original.as_pointer()
        if key in self.ids:
            return self.ids[key]
        self.attributes.used = set()
        try:
            program, volume, null_surface = self._translate(material)
        finally:
            used, self.attributes.used = self.attributes.used, None
        subject = "Material '%s'" % material.name
        mat_id = -1
        if self._bad:
            # One bad value leaves the material out, not the render: its objects get the default
            # surface, as an empty material slot.
            self.report({'WARNING'}, "%s left out: %s not finite; objects using it render with the default "
                        "surface (grey diffuse, as an empty material slot)" % (subject, ", ".join(self._bad)))
        elif program is not None:
            mat_id = core_call(self.core_scene, self.report, subject, "add_material", program)
            mat_id = -1 if mat_id is None else mat_id
            if mat_id >= 0 and material.pass_index:
                self.core_scene.set_material_pass_index(mat_id, material.pass_index)
            if mat_id >= 0:
                self.core_scene.set_material_cryptomatte(mat_id, self.cryptomatte.material(material))
            if mat_id >= 0 and self._displaced is not None:
                self.core_scene.set_material_displacement(mat_id, *self._displaced)
        if mat_id < 0:
            volume, null_surface = None, False
        elif volume:
            self.core_scene.set_material_volume(mat_id, volume, null_surface=null_surface)
            self.media += 1
            self.emissive_media += bool(emissive_nodes(volume))
        elif null_surface:
            # A volume-only material whose volume cannot be used: no medium, but the boundary stays
            # invisible (an empty medium), as the material would be without its volume in Cycles;
            # never an opaque black surface.
            self.core_scene.set_material_volume(mat_id, [dict(node=core.VOLUME_SCATTER, density=0.0)],
                                                null_surface=True)
        self.ids[key] = mat_id
        if mat_id >= 0:
            self.geometry_reads[mat_id] = frozenset(k for k in used if k[0] in ('attr', 'color', 'uv'))
        self.volumes[key] = (volume, null_surface)
        self.displacements[key] = _program_key(self._displaced if mat_id >= 0 else None)
        if volume:
            self.volume_names[mat_id] = material.name
        return mat_id

    def volume_name(self, mat_id):
        """The name of the material of core id `mat_id` if it has a medium, else None."""
        return self.volume_names.get(mat_id)

    def update(self, material):
        """Replaces an exported material's surface in a committed scene (viewport edits).

        Returns False when the edit needs a new scene: the material was not exported, its
        volume changed, or it now uses an image the scene does not have (core.LanternError).
        """
        key = material.original.as_pointer()
        if key not in self.ids:
            return False
        program, volume, null_surface = self._translate(material)
        if self._bad or program is None or self.ids[key] < 0 or self.volumes.get(key) != (volume, null_surface):
            return False  # a new scene, whose export reports the bad values
        if _program_key(self._displaced) != self.displacements.get(key):
            return False  # vertices move at the first commit only
        self.core_scene.set_material(self.ids[key], program)
        return True

    def view_layer_value(self, name):
        """The Attribute node's View Layer value of name (mesh.view_layer_value), recorded."""
        value = view_layer_value(self.depsgraph, name) if self.depsgraph is not None else (0.0, 0.0, 0.0, 0.0)
        self.view_layer_seen[name] = value
        return value

    def _compiler(self, material):
        c = nodes.Compiler(material.name, self.images, self._warn, camera=self.camera)
        c.attributes = self.attributes  # one numbering of attribute names per scene
        c.material_pass_index = material.pass_index
        c.ao_distance = self.ao_distance
        c.view_layer_value = self.view_layer_value
        return c

    def _displacement(self, material, output, method):
        """(program, core method) of the material's true displacement (methods Displacement Only
        and Displacement and Bump with the Displacement linked), or None."""
        method = _DISPLACEMENT_METHODS.get(method)
        disp = output.inputs.get("Displacement")
        if method is None or disp is None:
            return None
        c = self._compiler(material)
        if not c.linked(disp):
            return None
        program = c.compile_displacement(output)
        self._bad += c.bad
        return program, method

    def _translate(self, material):
        """(program or None, volume keywords or None, null surface) of a material; its true
        displacement in self._displaced ((program, method) or None)."""
        self._material = material
        self._bad = []  # the inputs whose values are not finite ("'Strength' of 'Emission'")
        self._displaced = None
        volume, null_surface = None, False
        c = self._compiler(material)
        try:
            if material.use_nodes and material.node_tree is not None:
                volume = self.volume(material)
                output = material.node_tree.get_output_node('CYCLES')
                if volume is not None and (output is None or not c.linked(output.inputs["Surface"])):
                    # Volume only: Cycles' invisible boundary (Transparent for the surface
                    # integrators), also when nothing in the volume can be used (reported).
                    if not volume:
                        self._warn("no usable volume shader; the volume is left out and its boundary "
                                   "stays invisible")
                    c.closure(nodes.ops.TRANSPARENT, [c.const((1.0, 1.0, 1.0)), c.const((1.0, 1.0, 1.0))])
                    null_surface = True
                elif output is None:
                    self._warn("no active Material Output node, rendered black")
                else:
                    method = getattr(getattr(material, "cycles", None), "displacement_method", 'BUMP')
                    c.compile_surface(output, method)
                    self._displaced = self._displacement(material, output, method)
                c.compile_aovs(material.node_tree, self.aovs)
            else:
                c.closure(nodes.ops.DIFFUSE, [c.const((1.0, 1.0, 1.0)), c.const((0.0, 0.0, 0.0)),
                                              c.const(tuple(material.diffuse_color[:3])), c.const(0.0)])
        except nodes.Unsupported as e:
            self._warn("%s; the material is left out (default surface)" % e)
            return None, None, False
        self._bad += c.bad
        if c.subsurface:
            self.subsurface.add(material.name)
        return c.program(), volume, null_surface

    def volume(self, material, attributes=False):
        """The material's Volume output as set_material_volume's components, [] (unusable) or None
        (attributes: a Volume object's, volume_keywords)."""
        self._material = material
        if not material.use_nodes or material.node_tree is None:
            return None
        components = volume_keywords(material.node_tree.get_output_node('CYCLES'), self._warn, attributes)
        bad = [c.get("name", "?") for c in components or () if not is_finite(*_numbers(c))]
        if bad:
            self._warn("volume %s left out: values not finite" % ", ".join("'%s'" % n for n in bad))
            return []
        return components

    def _warn(self, message):
        self.report({'WARNING'}, "Material '%s': %s" % (self._material.name, message))


def _numbers(component):
    """The numeric values of a volume component (set_material_volume's keywords)."""
    out = []
    for k, v in component.items():
        if k in ("node", "name") or isinstance(v, str):
            continue
        out.extend(v if isinstance(v, (tuple, list)) else (v,))
    return out


def _convert(v, colour):
    """A socket value as the receiving socket sees it: colour (3 floats) or scalar."""
    if isinstance(v, (float, int)):
        return (float(v),) * 3 if colour else float(v)
    v = tuple(v)[:3]
    if colour:
        return v
    return float(sum(c * w for c, w in zip(v, _LUMA)))
