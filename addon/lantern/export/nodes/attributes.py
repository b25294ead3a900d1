"""Nodes that read named attributes and object values (kOpAttribute... in the core's inputs.h):
UV Map, Color Attribute, Attribute, Tangent, Normal Map, Object Info.

Names become small ids, one numbering per scene (AttributeRegistry, shared by every material the
scene compiles); the mesh exporter then exports, for each mesh, only the attributes some compiled
program asked for (export/mesh.py: mesh_attributes)."""

from . import ops, register

DOMAIN_MESH, DOMAIN_OBJECT, DOMAIN_COLOR = 0, 1, 2


class AttributeRegistry:
    """Keys: ('attr', name) a mesh attribute by name (UV maps first, then Mesh.attributes);
    ('color', '') the default colour attribute; ('tangent', uv map name or '' for the active
    render map) a MikkTSpace tangent and its sign; ('object', name) a value of the object;
    ('instancer', name) a value of an instance's instancer, else of the object (Cycles names the
    two types apart)."""

    def __init__(self):
        self.ids = {}
        self.used = None  # a set: the keys asked for are added to it (one material's)

    def note(self, key):
        """A geometry value read without an id: ('uv', '') the default UV map (Texture Coordinate's
        UV), which curves export only when a material reads it."""
        if self.used is not None:
            self.used.add(key)

    def id(self, kind, name):
        key = (kind, name or "")
        if self.used is not None:
            self.used.add(key)
        if key not in self.ids:
            self.ids[key] = len(self.ids)
        return self.ids[key]

    def mesh_keys(self):
        return [(k, i) for k, i in self.ids.items() if k[0] not in _OBJECT_KINDS]

    def object_keys(self):
        """[(name, id, whether an instancer's value comes first)] of the object values."""
        return [(k[1], i, k[0] == 'instancer') for k, i in self.ids.items() if k[0] in _OBJECT_KINDS]


_OBJECT_KINDS = ('object', 'instancer')


def registry(c):
    """The compiler's registry (a private one when the caller gave none: tests)."""
    reg = getattr(c, "attributes", None)
    if reg is None:
        reg = c.attributes = AttributeRegistry()
    return reg


def _attribute(c, kind, name, domain):
    return c.emit(ops.ATTRIBUTE, [], [("Vector", 3), ("Fac", 1), ("Alpha", 1)],
                  params=[registry(c).id(kind, name), domain, c.bump])


def default_uv(c):
    """Texture Coordinate's UV output, noted as read (AttributeRegistry.note)."""
    registry(c).note(('uv', ''))
    return c.texcoord("UV")


@register('UVMAP')
def uv_map(c, node, want):
    if not node.uv_map:
        return {"UV": default_uv(c)}
    return {"UV": _attribute(c, 'attr', node.uv_map, DOMAIN_MESH)["Vector"]}


@register('VERTEX_COLOR')
def color_attribute(c, node, want):
    name = node.layer_name
    outs = _attribute(c, 'attr' if name else 'color', name, DOMAIN_COLOR)
    return {"Color": outs["Vector"], "Alpha": outs["Alpha"]}


@register('ATTRIBUTE')
def attribute(c, node, want):
    kind, domain = ('attr', DOMAIN_MESH)
    if node.attribute_type in ('OBJECT', 'INSTANCER'):
        kind, domain = node.attribute_type.lower(), DOMAIN_OBJECT
    elif node.attribute_type == 'VIEW_LAYER':
        # A constant of the render, as Cycles folds it: RGB, their mean as Fac, the fourth as Alpha.
        x, y, z, w = c.view_layer_value(node.attribute_name)
        return {"Color": c.const((x, y, z)), "Vector": c.const((x, y, z)), "Fac": c.const((x + y + z) / 3.0),
                "Alpha": c.const(w)}
    outs = _attribute(c, kind, node.attribute_name, domain)
    return {"Color": outs["Vector"], "Vector": outs["Vector"], "Fac": outs["Fac"], "Alpha": outs["Alpha"]}


_AXES = {'X': 0, 'Y': 1, 'Z': 2}


@register('TANGENT')
def tangent(c, node, want):
    uv = node.direction_type == 'UV_MAP'
    tid = registry(c).id('tangent', node.uv_map) if uv else 0
    return c.emit(ops.TANGENT, [], [("Tangent", 3)], params=[1 if uv else 0, _AXES.get(node.axis, 2), tid])


_SPACES = {'TANGENT': 0, 'OBJECT': 1, 'WORLD': 2, 'BLENDER_OBJECT': 3, 'BLENDER_WORLD': 4}


@register('NORMAL_MAP')
def normal_map(c, node, want):
    space = _SPACES.get(node.space, 0)
    tid = registry(c).id('tangent', node.uv_map) if space == 0 else 0
    return c.emit(ops.NORMAL_MAP, [c.float(node.inputs["Strength"]), c.color(node.inputs["Color"])],
                  [("Normal", 3)], params=[space, tid])


@register('OBJECT_INFO')
def object_info(c, node, want):
    outs = c.emit(ops.OBJECT_INFO, [], [("Location", 3), ("Color", 3), ("Alpha", 1), ("Object Index", 1),
                                        ("Random", 1)])
    outs["Material Index"] = c.const(float(getattr(c, "material_pass_index", 0)))
    return outs


# Cycles' hashes (util/hash.h), for Object Info's Random of objects that are not instances.

def _rot(x, k):
    return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF


def _lookup3_final(a, b, c):
    """Bob Jenkins' lookup3 final mix (Cycles' final())."""
    c ^= b
    c = (c - _rot(b, 14)) & 0xFFFFFFFF
    a ^= c
    a = (a - _rot(c, 11)) & 0xFFFFFFFF
    b ^= a
    b = (b - _rot(a, 25)) & 0xFFFFFFFF
    c ^= b
    c = (c - _rot(b, 16)) & 0xFFFFFFFF
    a ^= c
    a = (a - _rot(c, 4)) & 0xFFFFFFFF
    b ^= a
    b = (b - _rot(a, 14)) & 0xFFFFFFFF
    c ^= b
    c = (c - _rot(b, 24)) & 0xFFFFFFFF
    return c


def hash_uint(kx):
    """Cycles' hash_uint: lookup3's final mix of one word."""
    a = b = c = (0xdeadbeef + (1 << 2) + 13) & 0xFFFFFFFF
    return _lookup3_final((a + kx) & 0xFFFFFFFF, b, c)


def hash_uint2(kx, ky):
    """Cycles' hash_uint2: lookup3's final mix of two words."""
    a = b = c = (0xdeadbeef + (2 << 2) + 13) & 0xFFFFFFFF
    return _lookup3_final((a + kx) & 0xFFFFFFFF, (b + ky) & 0xFFFFFFFF, c)


def hash_string(s):
    """Cycles' hash_string: i = i * 37 + c over the UTF-8 bytes (chars are signed)."""
    i = 0
    for byte in s.encode("utf-8"):
        ch = byte - 256 if byte >= 128 else byte
        i = (i * 37 + ch) & 0xFFFFFFFF
    return i


def object_random_id(name):
    """Cycles' random id of an object that is not an instance (blender/object.cpp)."""
    return hash_uint2(hash_string(name), 0)
