"""Cryptomatte passes as Cycles 3.4 writes them (docs/passes.md): the same ids and manifests as
Cycles for the same scene, and mattes that Blender's own Cryptomatte node (Render source) decodes
into exactly the objects they name.

The scene is `textured` at 48 x 36 with Cube parented under Rig under Root (two empties at the
origin, so nothing moves): Cube's asset is Root, the top-most parent. Interior pixels are those
whose 5x5 neighbourhood shows one object in the IndexOB pass (every sample of such a pixel, within
the Blackman-Harris filter's 1.5 px, sees that object): there a pixel's first id is the object's
with coverage 1, in both engines.
"""
import json

import bpy
import numpy as np
import pytest

import render_utils as ru

LEVELS = 6  # Blender's default: 3 layers per type
INDEX = {"Floor": 1, "Cube": 2, "GlossyPanel": 3}


def _scene(scene_factory):
    scene = scene_factory("textured", resolution=(48, 36))
    root = bpy.data.objects.new("Root", None)
    rig = bpy.data.objects.new("Rig", None)
    for o in (root, rig):
        scene.collection.objects.link(o)
    rig.parent = root
    scene.objects["Cube"].parent = rig
    for name, index in INDEX.items():
        scene.objects[name].pass_index = index
    vl = scene.view_layers[0]
    vl.use_pass_object_index = True
    vl.use_pass_cryptomatte_object = vl.use_pass_cryptomatte_material = vl.use_pass_cryptomatte_asset = True
    vl.pass_cryptomatte_depth = LEVELS
    return scene


def _header_strings(path):
    with open(path, "rb") as f:
        header, _ = ru._read_header(f.read())
    return {k: v.decode("utf-8") for k, (t, v) in header.items() if t == "string"}


def _crypto_layers(path):
    """{"CryptoObject00": (h, w, 4) id, coverage, id, coverage}: Blender names these channels in
    lower case (r, g, b, a), which render_utils' reader would order alphabetically."""
    out = {}
    chans = ru.read_exr(path)
    for name in {c.split(".")[-2] for c in chans if ".Crypto" in c}:
        out[name] = np.stack([chans["ViewLayer.%s.%s" % (name, c)] for c in "rgba"], axis=-1)
    return out


def _interior(index, r=2):
    """Pixels whose (2r + 1)^2 neighbourhood shows one object: the filter's samples (within 1.5
    px of the centre) all land on it."""
    h, w = index.shape
    inner = np.zeros_like(index, dtype=bool)
    inner[r:-r, r:-r] = True
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            inner[r:-r, r:-r] &= index[r + dy:h - r + dy, r + dx:w - r + dx] == index[r:-r, r:-r]
    return inner


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    import build_scenes
    out = {}
    outdir = str(tmp_path_factory.mktemp("crypto"))
    for engine in (ru.CYCLES, ru.LANTERN):
        build_scenes.reset_file()
        scene = _scene(lambda name, **kw: build_scenes.build(name, **kw))
        r = ru.render(scene, engine, 16, seed=0, outdir=outdir, keep=True)
        r.update(_crypto_layers(r.path))
        out[engine] = (r, _header_strings(r.path))
    return out


def _manifests(headers):
    """{layer name: {object name: hex hash}} and the other keys, from a file's header."""
    layers = {}
    for key, value in headers.items():
        if key.startswith("cryptomatte/") and key.endswith("/name"):
            base = key[:-len("name")]
            assert headers[base + "hash"] == "MurmurHash3_32"
            assert headers[base + "conversion"] == "uint32_to_float32"
            layers[value] = json.loads(headers[base + "manifest"])
    return layers


def test_ids_and_manifests_equal_cycles(runs):
    (lr, lh), (cr, ch) = runs[ru.LANTERN], runs[ru.CYCLES]
    lm, cm = _manifests(lh), _manifests(ch)
    assert set(cm) == {"ViewLayer.CryptoObject", "ViewLayer.CryptoMaterial", "ViewLayer.CryptoAsset"}, cm
    assert set(lm) == set(cm), (lm, cm)
    # The same keys (the layer name's hash) as Cycles' and, for every name Lantern lists, Cycles' hash.
    assert {k for k in lh if k.startswith("cryptomatte/")} == {k for k in ch if k.startswith("cryptomatte/")}
    for layer, names in lm.items():
        for name, hex_id in names.items():
            assert cm[layer].get(name) == hex_id, (layer, name, hex_id, cm[layer])
    assert set(lm["ViewLayer.CryptoObject"]) == set(INDEX)
    assert set(lm["ViewLayer.CryptoAsset"]) == {"Floor", "Root", "GlossyPanel"}
    assert set(lm["ViewLayer.CryptoMaterial"]) == {"CheckerDiffuse", "BandedGlossy"}

    index = cr["IndexOB"][..., 0]
    inner = _interior(index) & (index > 0)
    assert inner.sum() > 0.3 * index.size
    for kind in ("CryptoObject", "CryptoMaterial", "CryptoAsset"):
        for k in range((LEVELS + 1) // 2):
            name = "%s%02d" % (kind, k)
            assert lr[name].shape == cr[name].shape, name
        # Interior pixels: one id, Cycles' float bit for bit, coverage 1.
        lids, cids = lr[kind + "00"][..., 0][inner], cr[kind + "00"][..., 0][inner]
        assert np.array_equal(lids.view(np.uint32), cids.view(np.uint32)), kind
        for r in (lr, cr):
            assert np.allclose(r[kind + "00"][..., 1][inner], 1.0, atol=1e-5), kind
            assert not r[kind + "00"][..., 2:][inner].any(), kind
        # Every id either engine writes anywhere is one of Cycles' manifest's (as a float).
        hashes = {int(v, 16) for v in cm["ViewLayer." + kind].values()}
        floats = {np.array([h], np.uint32).view(np.float32)[0] for h in hashes}
        floats = {np.uint32(np.array([f], np.float32).view(np.uint32)[0]) for f in floats}
        for r in (lr, cr):
            ids = np.concatenate([r["%s%02d" % (kind, k)][..., c].ravel()
                                  for k in range((LEVELS + 1) // 2) for c in (0, 2)])
            seen = {np.uint32(b) for b in ids[ids != 0].view(np.uint32)}
            assert seen <= floats, (kind, seen - floats)


def _matte(scene, layer, names, outdir):
    """The Cryptomatte node's Matte for `names` from the render result, as a compositor tree in
    the render writes it (File Output, float EXR)."""
    import os
    import tempfile
    scene.use_nodes = True
    scene.render.use_compositing = True
    tree = scene.node_tree
    tree.nodes.clear()
    rl = tree.nodes.new("CompositorNodeRLayers")
    rl.scene = scene
    crypto = tree.nodes.new("CompositorNodeCryptomatteV2")
    crypto.source = 'RENDER'
    crypto.scene = scene
    crypto.layer_name = "ViewLayer." + layer
    crypto.matte_id = ",".join(names)
    out = tree.nodes.new("CompositorNodeOutputFile")
    out.base_path = tempfile.mkdtemp(dir=outdir)
    out.format.file_format = 'OPEN_EXR'
    out.format.color_depth = '32'
    out.format.exr_codec = 'ZIP'
    out.file_slots[0].path = "matte"
    comp = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(rl.outputs["Image"], crypto.inputs["Image"])
    tree.links.new(crypto.outputs["Matte"], out.inputs[0])
    tree.links.new(rl.outputs["Image"], comp.inputs["Image"])
    bpy.ops.render.render(write_still=False, scene=scene.name)
    path = os.path.join(out.base_path, "matte%04d.exr" % scene.frame_current)
    return ru.read_multilayer_exr(path)["Combined"][..., 0]


def test_compositor_mattes_isolate_the_named_objects(scene_factory, outdir):
    scene = _scene(scene_factory)
    r = ru.render(scene, ru.LANTERN, 16, seed=0)
    index = r["IndexOB"][..., 0]
    inner = _interior(index)
    cube = _matte(scene, "CryptoObject", ["Cube"], outdir)
    assert cube.shape == index.shape
    # Interior pixels: exactly the object (1 on it, 0 elsewhere); edges fractional, within [0, 1].
    want = (index == INDEX["Cube"]).astype(np.float32)
    wrong = inner & (np.abs(cube - want) > 1e-5)
    assert not wrong.any(), "%d interior pixels, e.g. %s: matte %s, IndexOB %s" % (
        wrong.sum(), np.argwhere(wrong)[0], cube[wrong][0], index[wrong][0])
    assert (want[inner] == 1).sum() > 20 and (want[inner] == 0).sum() > 20
    edge = ~inner
    assert ((cube[edge] > 0.01) & (cube[edge] < 0.99)).sum() > 5, "no fractional edge pixels"
    assert cube.min() >= -1e-6 and cube.max() <= 1 + 1e-5
    # The asset Root is Cube's top-most parent: the same matte; the material CheckerDiffuse is Cube's
    # and Floor's.
    assert np.allclose(_matte(scene, "CryptoAsset", ["Root"], outdir), cube, atol=1e-6)
    both = _matte(scene, "CryptoMaterial", ["CheckerDiffuse"], outdir)
    want = np.isin(index, [INDEX["Cube"], INDEX["Floor"]]).astype(np.float32)
    assert not (inner & (np.abs(both - want) > 1e-5)).any()
