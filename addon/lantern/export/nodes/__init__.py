"""Material and World node trees compiled into shader programs for the core's register machine
(native/src/shading/program.h documents the encoding).

The compiler walks back from the Material (or World) Output's Surface socket: node groups are flattened
(a group node's inside is compiled in the scope of that group node), reroutes and muted nodes are
followed, each node is compiled once per scope, and the core folds the instructions whose inputs
are all constant. Shader sockets are compiled with the weight Mix Shader gives them (the closure
weight); value sockets into registers. Node families register their compilers here with
`@register(node.type)`: value nodes `fn(c, node, want) -> {output name: operand}`, shader nodes
with `@register_shader(node.type)`: `fn(c, node, weight)`.
"""

import struct

from . import opcodes as ops

CONST_BIT = 0x80000000
MAX_REGISTERS = 4096
MAX_CLOSURES = 1024

# Rec. 709 luma, as Blender converts a colour into a float socket.
LUMA = (0.2126, 0.7152, 0.0722)

VALUE_NODES = {}
SHADER_NODES = {}
# Nodes whose outgoing links Cycles 3.4 drops (EEVEE-only nodes it has no node for): the inputs they
# feed keep their own values, in Cycles and here (measured: an Emission's Color and Strength fed
# by Shader to RGB's Color and Alpha render with their socket defaults).
CYCLES_DROPS = {'SHADERTORGB'}


def register(*types):
    def wrap(fn):
        for t in types:
            VALUE_NODES[t] = fn
        return fn
    return wrap


def register_shader(*types):
    def wrap(fn):
        for t in types:
            SHADER_NODES[t] = fn
        return fn
    return wrap


def size_of(operand):
    return (operand >> 24) & 0xF


class Unsupported(Exception):
    """A node the compiler cannot express; the caller falls back as documented."""


def _is_vector_type(t):
    return t in ('RGBA', 'VECTOR')


# Shader nodes that mean something in a world: Cycles reads only the emission of a world's
# closures (shader_background_eval); Background and Emission are the same closure there.
WORLD_SHADERS = {'BACKGROUND', 'EMISSION', 'MIX_SHADER', 'ADD_SHADER'}


class Compiler:
    """Compiles one material's (or, with world=True, one world's) surface. `warn(text)` receives
    messages naming the node; the material's or world's name is added by the caller."""

    def __init__(self, material_name, images, warn, camera=None, world=False):
        self.material_name = material_name
        self.world = world
        self.subject = ("World '%s'" if world else "Material '%s'") % material_name
        self.images = images
        self._warn = warn
        self.camera = camera  # 28 floats for Texture Coordinate's Camera and Window, or None
        self.ao_distance = 10.0  # the World's AO distance (Ambient Occlusion's Distance 0), Blender's default
        # The Attribute node's View Layer values: name -> 4 floats (mesh.view_layer_value); none
        # without a depsgraph (tests compiling alone).
        self.view_layer_value = lambda name: (0.0, 0.0, 0.0, 0.0)
        self.code = []
        self.constants = []
        self._const_ids = {}
        self.registers = 0
        self._memo = {}
        self._scope = ()
        self._active = set()  # nodes being compiled: a link back to one is a cycle
        self._closures = 0
        self._flags = {}  # output operand -> code word set to 1 when the output is read
        # 0: the shading point; 1, 2: moved by its differentials (Bump's copies of its Height
        # input, as Cycles' SHADER_BUMP_DX / DY): position-reading ops take it as a param.
        self.bump = 0
        self._warned = set()
        self.bad = []  # non-finite socket values ("'Strength' of 'Emission' (inf)")
        self.subsurface = False  # a closure scatters under the surface (BIDIRECTIONAL: radius 0)

    # -- program building -----------------------------------------------------------------------

    def warn(self, text):
        if text not in self._warned:
            self._warned.add(text)
            self._warn(text)

    def const(self, value):
        """An operand for a constant float or 3-vector."""
        if isinstance(value, (int, float)):
            values = (float(value),)
        else:
            values = tuple(float(v) for v in value)[:3]
            values += (0.0,) * (3 - len(values))
        values = tuple(v if v == v and abs(v) != float('inf') else 0.0 for v in values)
        # Pack to float32 so equal constants share one slot.
        key = struct.pack("%df" % len(values), *values)
        if key not in self._const_ids:
            self._const_ids[key] = len(self.constants)
            self.constants.extend(values)
        return CONST_BIT | (len(values) << 24) | self._const_ids[key]

    def table(self, values):
        """A table in the constant pool (its length first); returns its offset for a 't' param."""
        offset = len(self.constants)
        self.constants.append(float(len(values)))
        self.constants.extend(float(v) for v in values)
        return offset

    def emit(self, op, inputs, outputs=(), params=()):
        """Appends an instruction; outputs: (name, size) pairs. Returns {name: operand}."""
        result = {}
        out_words = []
        for name, size in outputs:
            if self.registers + size > MAX_REGISTERS:
                raise Unsupported("the material needs more than %d registers" % MAX_REGISTERS)
            word = (size << 24) | self.registers
            self.registers += size
            result[name] = word
            out_words.append(word)
        self.code.append(int(op))
        self.code.append(len(inputs) | (len(out_words) << 8) | (len(params) << 16))
        self.code.extend(int(w) for w in inputs)
        self.code.extend(out_words)
        self.code.extend(int(p) & 0xFFFFFFFF for p in params)
        return result

    def on_read(self, operand, word):
        """Sets code[word] to 1 once `operand` is read by another node (flags like Cycles'
        NODE_IMAGE_ALPHA_UNASSOCIATE, which depend on whether an output is used)."""
        self._flags[operand] = word

    def texcoord(self, name, object_table=()):
        """An output of Texture Coordinate ('Generated', 'UV', ...); object_table: another object's
        world-to-object matrix (12 floats) for its Object output."""
        key = ('texcoord', tuple(object_table), self.bump)
        if key not in self._memo:
            self._memo[key] = self.emit(
                ops.TEX_COORD, [], [(n, 3) for n in TEX_COORD_OUTPUTS],
                params=[self.table(list(object_table)), self.table(self.camera or []), self.bump])
        return self._memo[key][name]

    def geometry(self):
        """The Geometry instruction's outputs {name: operand}."""
        key = ('geometry', self.bump)
        if key not in self._memo:
            self._memo[key] = self.emit(ops.GEOMETRY, [], GEOMETRY_OUTPUTS, params=[self.bump])
        return self._memo[key]

    def heights(self, socket, read=None):
        """A float input at the shading point and moved by each of its differentials (Bump);
        read(socket) -> operand replaces self.float (the Displacement output's height)."""
        saved = self.bump
        try:
            out = []
            for k in (0, 1, 2):
                self.bump = k
                out.append((read or self.float)(socket))
            return out
        finally:
            self.bump = saved

    # -- sockets --------------------------------------------------------------------------------

    def follow(self, socket):
        """(scope, output socket) feeding an input socket in the current scope, through
        reroutes, muted nodes and node groups; (scope, None, input socket) when it is unlinked
        (its default value, possibly a group node's socket, is used)."""
        scope = self._scope
        for _ in range(4096):
            links = [l for l in socket.links if l.is_valid and not l.is_muted]
            if not links:
                return scope, None, socket
            out = links[0].from_socket
            node = out.node
            if node.type == 'REROUTE':
                socket = node.inputs[0]
                continue
            if node.mute:
                # A muted node passes its internal link's input through, or gives nothing.
                nxt = next((l.from_socket for l in node.internal_links if l.to_socket == out), None)
                if nxt is None:
                    return scope, None, None
                socket = nxt
                continue
            if node.type in CYCLES_DROPS:
                self.warn("'%s' (%s) is an EEVEE node that Cycles does not render: the sockets it feeds "
                          "keep their own values, as in Cycles" % (node.name, node.bl_idname))
                return scope, None, socket
            if node.type == 'GROUP':
                tree = node.node_tree
                group_out = _group_output(tree)
                if tree is None or group_out is None:
                    self.warn("node group '%s' has no Group Output; its outputs are 0" % node.name)
                    return scope, None, None
                inner = next((s for s in group_out.inputs if s.identifier == out.identifier), None)
                if inner is None:
                    return scope, None, None
                scope = scope + (node,)
                socket = inner
                continue
            if node.type == 'GROUP_INPUT':
                if not scope:
                    return scope, None, None
                group_node = scope[-1]
                outer = next((s for s in group_node.inputs if s.identifier == out.identifier), None)
                scope = scope[:-1]
                if outer is None:
                    return scope, None, None
                socket = outer
                continue
            return scope, out, None
        raise Unsupported("links loop through reroutes or groups more than 4096 times")

    def _value(self, socket, size):
        """Operand for an input socket as a float (size 1) or a 3-vector (colour or vector)."""
        if socket is None:
            return self.const(0.0 if size == 1 else (0.0, 0.0, 0.0))
        scope, out, unlinked = self.follow(socket)
        if out is None:
            return self._default(unlinked, size)
        if out.node.type in ('VALUE', 'RGB'):
            v = out.default_value
            values = (v,) if isinstance(v, float) else tuple(v)
            if not all(_finite(x) for x in values):
                self.bad.append("'%s' of '%s' (%s from '%s')" % (socket.name, socket.node.name,
                                                                  values[0] if len(values) == 1 else values,
                                                                  out.node.name))
        saved = self._scope
        self._scope = scope
        try:
            operand = self._output(out)
        finally:
            self._scope = saved
        return self.convert(operand, size, out.type)

    def _default(self, socket, size):
        if socket is None or not hasattr(socket, "default_value"):
            return self.const(0.0 if size == 1 else (0.0, 0.0, 0.0))
        v = socket.default_value
        if isinstance(v, (int, float, bool)):
            v = float(v)
            if not _finite(v):
                self.bad.append("'%s' of '%s' (%s)" % (socket.name, socket.node.name, v))
            return self.const(v if size == 1 else (v, v, v))
        v = tuple(v)
        if not all(_finite(x) for x in v):
            self.bad.append("'%s' of '%s' (%s)" % (socket.name, socket.node.name, v))
        if size == 3:
            return self.const(v[:3])
        if socket.type == 'RGBA':
            return self.const(sum(c * w for c, w in zip(v[:3], LUMA)))
        return self.const(sum(v[:3]) / 3.0)

    def convert(self, operand, size, from_type):
        have = size_of(operand)
        if have == size:
            return operand
        if size == 3:
            return self.emit(ops.TO_VECTOR, [operand], [("v", 3)])["v"]
        return self.emit(ops.TO_FLOAT, [operand], [("f", 1)],
                         params=[0 if from_type == 'RGBA' else 1])["f"]

    def float(self, socket):
        return self._value(socket, 1)

    def vector(self, socket, default=None):
        """A vector input; `default` (an operand) replaces an unlinked socket's value (texture
        nodes' implicit coordinates)."""
        if default is not None and socket is not None and self.follow(socket)[1] is None:
            return default
        return self._value(socket, 3)

    color = vector

    def normal(self, socket):
        """A Normal input: (0, 0, 0), the core's stand-in for the shading normal, when unlinked."""
        if socket is None or self.follow(socket)[1] is None:
            return self.const((0.0, 0.0, 0.0))
        return self._value(socket, 3)

    def linked(self, socket):
        return socket is not None and self.follow(socket)[1] is not None

    def _output(self, out):
        node = out.node
        key = (tuple(n.as_pointer() for n in self._scope), node.as_pointer(), self.bump)
        if key in self._active:
            raise Unsupported("the node tree has a cycle through '%s'" % node.name)
        if key not in self._memo:
            self._active.add(key)
            try:
                self._memo[key] = self._compile_value_node(node, out)
            finally:
                self._active.discard(key)
        outputs = self._memo[key]
        operand = outputs.get(out.name, outputs.get(out.identifier))
        if operand is not None:
            if operand in self._flags:
                self.code[self._flags.pop(operand)] = 1
            return operand
        self.warn("output '%s' of '%s' (%s) is not supported; 0 is used" % (out.name, node.name, node.bl_idname))
        return self.const(0.0 if out.type == 'VALUE' else (0.0, 0.0, 0.0))

    def _compile_value_node(self, node, want):
        fn = VALUE_NODES.get(node.type)
        if fn is not None:
            return fn(self, node, want)
        # Unsupported: pass the internal link's input through where Blender defines one.
        passed = {}
        for link in node.internal_links:
            size = 1 if link.to_socket.type == 'VALUE' else 3
            passed[link.to_socket.name] = self._value(link.from_socket, size)
        self.warn("node '%s' (%s) is not supported; %s" % (
            node.name, node.bl_idname,
            "its input passes through" if passed else "its outputs are 0"))
        return passed

    # -- shaders --------------------------------------------------------------------------------

    def shader(self, socket, weight):
        """Compiles the closures feeding a shader socket with closure weight `weight`."""
        if socket is None:
            return
        scope, out, _ = self.follow(socket)
        if out is None:
            return
        node = out.node
        saved = self._scope
        self._scope = scope
        try:
            fn = SHADER_NODES.get(node.type)
            if self.world and node.type not in WORLD_SHADERS:
                self.warn("shader node '%s' (%s) gives no light in a world (Cycles uses only Background and "
                          "Emission there); left out" % (node.name, node.bl_idname))
                return
            if fn is None:
                self.warn("shader node '%s' (%s) is not supported; replaced by grey diffuse (0.5)"
                          % (node.name, node.bl_idname))
                self.closure(ops.DIFFUSE, [weight, self.const((0.0, 0.0, 0.0)),
                                           self.const((0.5, 0.5, 0.5)), self.const(0.0)])
                return
            fn(self, node, weight)
        finally:
            self._scope = saved

    def closure(self, op, inputs, params=()):
        self._closures += 1
        if self._closures > MAX_CLOSURES:
            raise Unsupported("the material expands to more than %d closures (shader nodes repeated "
                              "for each Mix or Add Shader input they feed)" % MAX_CLOSURES)
        self.emit(op, inputs, params=params)

    def compile_surface(self, output_node, displacement_method='BUMP'):
        """The program for a Material (or World) Output's Surface input, after its Displacement as
        bump (Cycles bumps for the methods Bump and Both, not for Displacement Only)."""
        disp = output_node.inputs.get("Displacement")
        if disp is not None and self.linked(disp) and displacement_method != 'DISPLACEMENT':
            self.displacement_bump(disp, undisplaced=displacement_method == 'BOTH')
        self.shader(output_node.inputs["Surface"], self.const((1.0, 1.0, 1.0)))
        return self.program()

    def compile_displacement(self, output_node):
        """The true-displacement program (Cycles' SHADER_TYPE_DISPLACEMENT): the Material Output's
        Displacement, a world-space offset, into SetDisplacement (the core moves vertices by it)."""
        self.emit(ops.SET_DISPLACEMENT, [self.vector(output_node.inputs["Displacement"])])
        return self.program()

    def compile_aovs(self, tree, aovs, scope=()):
        """Cycles' AOV Output nodes of `tree`, at its top level and inside its node groups (Cycles
        flattens the groups, blender/shader.cpp, and keeps every AOV Output with what feeds it):
        each adds the view-layer AOV of its name (aovs: name -> (index, colour), aov_indices;
        Blender 3.4 keeps the name in the node's `name`), its Color input for a colour AOV, its Value
        for a value one; one naming no AOV of the view layer writes nothing, as in Cycles."""
        for node in tree.nodes:
            if node.mute:
                continue
            if node.type == 'GROUP':
                if node.node_tree is not None and len(scope) < 64:  # Blender refuses recursive groups
                    self.compile_aovs(node.node_tree, aovs, scope + (node,))
                continue
            found = aovs.get(getattr(node, "aov_name", node.name)) if node.type == 'OUTPUT_AOV' else None
            if found is None:
                continue
            index, colour = found
            saved = self._scope
            self._scope = scope
            try:
                if colour:
                    self.emit(ops.AOV_COLOR, [self.color(node.inputs["Color"])], params=[index])
                else:
                    self.emit(ops.AOV_VALUE, [self.float(node.inputs["Value"])], params=[index])
            finally:
                self._scope = saved

    def displacement_bump(self, socket, undisplaced=False):
        """Cycles 3.4's bump from displacement (scene/shader_graph.cpp bump_from_displacement): the
        displacement's component along the normal (its dot with Geometry's Normal) at the point and
        moved by each differential, into a Bump of Distance 1 and Strength 1 whose normal becomes
        the shading point's (SetNormal) for everything the surface compiles after it. undisplaced
        (the method Displacement and Bump, on a mesh whose vertices moved): Cycles evaluates it
        at the undisplaced point (svm_node_enter_bump_eval) and bumps in object space."""
        from .converters import VECTOR_MATH_OPS
        if undisplaced:
            self.emit(ops.BUMP_EVAL, [], params=[0])
        normal = self.geometry()["Normal"]

        def height(s):
            dot = self.emit(ops.VECTOR_MATH, [self.vector(s), normal, self.const((0.0, 0.0, 0.0)),
                                              self.const(1.0)], [("Vector", 3), ("Value", 1)],
                            params=[VECTOR_MATH_OPS.index('DOT_PRODUCT')])
            return dot["Value"]
        heights = self.heights(socket, height)
        one = self.const(1.0)
        bumped = self.emit(ops.BUMP, [one, one] + heights + [self.const((0.0, 0.0, 0.0))], [("Normal", 3)],
                           params=[2 if undisplaced else 0])
        if undisplaced:
            self.emit(ops.BUMP_EVAL, [], params=[1])
        self.emit(ops.SET_NORMAL, [bumped["Normal"]])
        # Nodes the surface shares with the displacement see the new normal: compile them anew
        # (Cycles copies the displacement's nodes for its bump).
        self._memo = {}

    def program(self):
        return self.code, self.constants, self.registers


TEX_COORD_OUTPUTS = ("Generated", "Normal", "UV", "Object", "Camera", "Window", "Reflection")
GEOMETRY_OUTPUTS = [("Position", 3), ("Normal", 3), ("Tangent", 3), ("True Normal", 3), ("Incoming", 3),
                    ("Parametric", 3), ("Backfacing", 1), ("Pointiness", 1), ("Random Per Island", 1)]


def _finite(v):
    return v == v and abs(v) != float('inf')


def _group_output(tree):
    if tree is None:
        return None
    outs = [n for n in tree.nodes if n.type == 'GROUP_OUTPUT']
    return next((n for n in outs if n.is_active_output), outs[0] if outs else None)


def constant_program(op, inputs_fn):
    """A one-closure program (tests and the default surface): `inputs_fn(compiler)` gives the
    operands after the weight."""
    c = Compiler("", None, lambda _t: None)
    c.closure(op, [c.const((1.0, 1.0, 1.0))] + inputs_fn(c))
    return c.program()


# The families register their nodes on import.
from . import converters as _converters, inputs as _inputs, shaders as _shaders  # noqa: E402,F401
from . import attributes as _attributes, textures as _textures  # noqa: E402,F401
