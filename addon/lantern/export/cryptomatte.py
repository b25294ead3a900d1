"""Cryptomatte ids and manifests (docs/passes.md): the names Cycles 3.4 hashes (an object's name,
its material's, its asset's: the top-most parent's), their MurmurHash3 from the core, and the
metadata the Cryptomatte specification puts beside the passes."""

import json

from .. import core

# (Blender pass name prefix, lt_cryptomatte bit, view-layer toggle), in the order of the passes.
TYPES = (
    ("CryptoObject", core.CRYPTOMATTE_OBJECT, "use_pass_cryptomatte_object"),
    ("CryptoMaterial", core.CRYPTOMATTE_MATERIAL, "use_pass_cryptomatte_material"),
    ("CryptoAsset", core.CRYPTOMATTE_ASSET, "use_pass_cryptomatte_asset"),
)


def asset_name(obj):
    """An object's Cryptomatte asset: its top-most parent (itself without a parent)."""
    while obj.parent is not None:
        obj = obj.parent
    return obj.name


class Names:
    """The names an export gives ids to, per pass prefix, with their hashes (a manifest each)."""

    def __init__(self):
        self.manifests = {prefix: {} for prefix, _, _ in TYPES}

    def _hash(self, prefix, name):
        m = self.manifests[prefix]
        if name not in m:
            m[name] = core.cryptomatte_hash(name)
        return m[name]

    def instance(self, obj):
        """(object hash, asset hash) for lt_instance_desc."""
        return self._hash("CryptoObject", obj.name), self._hash("CryptoAsset", asset_name(obj))

    def material(self, material):
        return self._hash("CryptoMaterial", material.name)


def metadata(manifests, layer_prefix, kept):
    """The specification's keys for each kept type (an lt_cryptomatte bit mask): cryptomatte/<the
    first 7 hex digits of the hash of the layer's name>/name, hash, conversion, manifest (JSON of
    name -> 8 hex digits), as Cycles stamps them (layer_prefix "ViewLayer." in Blender's render
    result; "" in Lantern's own EXR parts, whose channels are CryptoObject00.r, ...)."""
    out = {}
    for prefix, bit, _ in TYPES:
        if not kept & bit:
            continue
        name = layer_prefix + prefix
        key = "cryptomatte/%s/" % ("%08x" % core.cryptomatte_hash(name))[:7]
        manifest = manifests.get(prefix, {})
        out[key + "name"] = name
        out[key + "hash"] = "MurmurHash3_32"
        out[key + "conversion"] = "uint32_to_float32"
        out[key + "manifest"] = json.dumps({n: "%08x" % h for n, h in sorted(manifest.items())},
                                           separators=(",", ":"), ensure_ascii=False)
    return out
