"""Shader nodes: closures with the weight Mix Shader hands them (shaders.h in the core)."""

from . import ops, register_shader

_DISTRIBUTIONS = {'SHARP': ops.DIST_SHARP, 'GGX': ops.DIST_GGX, 'BECKMANN': ops.DIST_BECKMANN,
                  'ASHIKHMIN_SHIRLEY': ops.DIST_ASHIKHMIN_SHIRLEY,
                  'MULTI_GGX': ops.DIST_MULTI_GGX}


def _distribution(node):
    return _DISTRIBUTIONS.get(getattr(node, "distribution", 'GGX'), ops.DIST_GGX)


@register_shader('MIX_SHADER')
def mix_shader(c, node, weight):
    w = c.emit(ops.MIX_WEIGHTS, [weight, c.float(node.inputs[0])], [("a", 3), ("b", 3)])
    c.shader(node.inputs[1], w["a"])
    c.shader(node.inputs[2], w["b"])


@register_shader('ADD_SHADER')
def add_shader(c, node, weight):
    c.shader(node.inputs[0], weight)
    c.shader(node.inputs[1], weight)


# Cycles' background_setup and emission_setup are the same closure (kernel/closure/emissive.h): a
# Background node emits colour x strength, in a world or on a surface.
@register_shader('EMISSION', 'BACKGROUND')
def emission(c, node, weight):
    c.closure(ops.EMISSION, [weight, c.color(node.inputs["Color"]), c.float(node.inputs["Strength"])])


@register_shader('BSDF_DIFFUSE')
def diffuse(c, node, weight):
    c.closure(ops.DIFFUSE, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                            c.float(node.inputs["Roughness"])])


@register_shader('BSDF_GLOSSY')
def glossy(c, node, weight):
    c.closure(ops.GLOSSY, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                           c.float(node.inputs["Roughness"])], params=[_distribution(node)])


@register_shader('BSDF_GLASS')
def glass(c, node, weight):
    _ior_warning(c, node)
    c.closure(ops.GLASS, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                          c.float(node.inputs["Roughness"]), c.float(node.inputs["IOR"])],
              params=[_distribution(node)])


# Cycles 3.4's CLOSURE_BSDF_REFRACTION_ID and MICROFACET_{GGX,BECKMANN}_REFRACTION_ID: refraction
# alone, weighted by the Color without Fresnel.
@register_shader('BSDF_REFRACTION')
def refraction(c, node, weight):
    _ior_warning(c, node, "seen from outside it lets almost no light through")
    c.closure(ops.REFRACTION, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                               c.float(node.inputs["Roughness"]), c.float(node.inputs["IOR"])],
              params=[_distribution(node)])


@register_shader('BSDF_ANISOTROPIC')
def anisotropic(c, node, weight):
    c.closure(ops.ANISOTROPIC, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                                c.float(node.inputs["Roughness"]), c.float(node.inputs["Anisotropy"]),
                                c.float(node.inputs["Rotation"]), c.normal(node.inputs.get("Tangent"))],
              params=[_distribution(node)])


@register_shader('BSDF_VELVET')
def velvet(c, node, weight):
    c.closure(ops.VELVET, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                           c.float(node.inputs["Sigma"])])


@register_shader('BSDF_TRANSLUCENT')
def translucent(c, node, weight):
    c.closure(ops.TRANSLUCENT, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"])])


@register_shader('BSDF_TOON')
def toon(c, node, weight):
    c.closure(ops.TOON, [weight, c.normal(node.inputs.get("Normal")), c.color(node.inputs["Color"]),
                         c.float(node.inputs["Size"]), c.float(node.inputs["Smooth"])],
              params=[1 if node.component == 'GLOSSY' else 0])


@register_shader('BSDF_TRANSPARENT')
def transparent(c, node, weight):
    c.closure(ops.TRANSPARENT, [weight, c.color(node.inputs["Color"])])


@register_shader('HOLDOUT')
def holdout(c, node, weight):
    c.closure(ops.HOLDOUT, [weight])


def _ior_warning(c, node, effect="a near-perfect mirror"):
    s = node.inputs["IOR"]
    if not c.linked(s) and not s.default_value > 0:
        c.warn("'%s' has IOR %g; rendered as IOR 0.00001 (as Cycles): %s" % (node.name, s.default_value, effect))


# Principled BSDF inputs in the core's order (shaders.h); Blender 4 names second.
_PRINCIPLED = (
    ("Base Color", 3), ("Subsurface", 1), ("Subsurface Radius", 3), ("Subsurface Color", 3),
    ("Subsurface IOR", 1), ("Subsurface Anisotropy", 1), ("Metallic", 1), ("Specular", 1),
    ("Specular Tint", 1), ("Roughness", 1), ("Anisotropic", 1), ("Anisotropic Rotation", 1),
    ("Sheen", 1), ("Sheen Tint", 1), ("Clearcoat", 1), ("Clearcoat Roughness", 1), ("IOR", 1),
    ("Transmission", 1), ("Transmission Roughness", 1), ("Emission", 3), ("Emission Strength", 1),
    ("Alpha", 1),
)
_ALIASES = {"Specular": "Specular IOR Level", "Transmission": "Transmission Weight",
            "Emission": "Emission Color", "Subsurface": "Subsurface Weight",
            "Clearcoat": "Coat Weight", "Sheen": "Sheen Weight"}


@register_shader('BSDF_PRINCIPLED')
def principled(c, node, weight):
    inp = node.inputs

    def socket(name):
        return inp.get(name) or inp.get(_ALIASES.get(name, name))

    ignored = []
    if c.linked(inp.get("Clearcoat Normal")):
        ignored.append("Clearcoat Normal (the clearcoat uses the Normal input)")
    if ignored:
        c.warn("Principled BSDF '%s': %s not supported, ignored" % (node.name, ", ".join(ignored)))
    sss = socket("Subsurface")
    if sss is not None and (c.linked(sss) or sss.default_value > 0):
        c.subsurface = True
    _ior_warning(c, node)
    operands = [weight, c.normal(inp.get("Normal"))]
    for name, size in _PRINCIPLED:
        s = socket(name)
        # Cycles 3.4 gives the refraction a roughness of its own only with GGX (its Multiscatter
        # GGX glass takes Roughness): 0 leaves it the Roughness.
        if name == "Transmission Roughness" and node.distribution != 'GGX':
            s = None
        operands.append(c._value(s, size) if s is not None else c.const(0.0 if size == 1 else (0.0,) * 3))
    operands.append(c.normal(inp.get("Clearcoat Normal")))
    operands.append(c.normal(inp.get("Tangent")))
    c.closure(ops.PRINCIPLED, operands,
              params=[_distribution(node), _SSS_METHODS.get(getattr(node, "subsurface_method", ""),
                                                               ops.SSS_RANDOM_WALK)])


# Cycles 3.4's subsurface methods (Principled subsurface_method, Subsurface Scattering falloff).
_SSS_METHODS = {'BURLEY': ops.SSS_BURLEY, 'RANDOM_WALK_FIXED_RADIUS': ops.SSS_RANDOM_WALK_FIXED_RADIUS,
                'RANDOM_WALK': ops.SSS_RANDOM_WALK}


@register_shader('SUBSURFACE_SCATTERING')
def subsurface_scattering(c, node, weight):
    i = node.inputs
    c.subsurface = True
    c.closure(ops.SUBSURFACE, [weight, c.normal(i.get("Normal")), c.color(i["Color"]), c.float(i["Scale"]),
                               c.vector(i["Radius"]), c.float(i["IOR"]), c.float(i["Anisotropy"])],
              params=[_SSS_METHODS.get(node.falloff, ops.SSS_RANDOM_WALK)])


_HAIR_PARAMETRIZATIONS = {'COLOR': ops.HAIR_REFLECTANCE, 'MELANIN': ops.HAIR_MELANIN,
                          'ABSORPTION': ops.HAIR_ABSORPTION}


@register_shader('BSDF_HAIR_PRINCIPLED')
def principled_hair(c, node, weight):
    i = node.inputs
    random = i["Random"]
    c.closure(ops.PRINCIPLED_HAIR,
              [weight, c.color(i["Color"]), c.float(i["Melanin"]), c.float(i["Melanin Redness"]),
               c.color(i["Tint"]), c.vector(i["Absorption Coefficient"]), c.float(i["Roughness"]),
               c.float(i["Radial Roughness"]), c.float(i["Coat"]), c.float(i["IOR"]), c.float(i["Offset"]),
               c.float(i["Random Color"]), c.float(i["Random Roughness"]), c.float(random)],
              params=[_HAIR_PARAMETRIZATIONS.get(node.parametrization, ops.HAIR_REFLECTANCE),
                      1 if c.linked(random) else 0])


@register_shader('BSDF_HAIR')
def hair(c, node, weight):
    i = node.inputs
    c.closure(ops.HAIR_BSDF, [weight, c.color(i["Color"]), c.float(i["Offset"]), c.float(i["RoughnessU"]),
                              c.float(i["RoughnessV"]), c.normal(i.get("Tangent"))],
              params=[1 if node.component == 'Transmission' else 0])
