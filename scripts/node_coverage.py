"""Lists, for a .blend, every shader node Lantern does not render (issue 13's coverage script).

    blender -b FILE.blend --python scripts/node_coverage.py [-- --all]

For each material and world (node groups included, each group once), prints the nodes whose type the
add-on's compiler has no rule for, with where they are; --all also lists the supported ones. Exits 0
always (it reports, it does not judge). It reads the compiler of the checkout it lives in (not an
installed copy of the add-on, which may be older).
"""
import os
import sys

import bpy

ADDON = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "addon")
sys.path.insert(0, ADDON)
_loaded = sys.modules.get("lantern")
if _loaded is not None and not os.path.abspath(_loaded.__file__).startswith(ADDON + os.sep):
    # An installed copy was imported first (Blender's add-on folder): read this checkout's.
    for name in [m for m in sys.modules if m == "lantern" or m.startswith("lantern.")]:
        del sys.modules[name]

from lantern.export import nodes  # noqa: E402

# Nodes that only route: the compiler follows them, they never render.
STRUCTURAL = {'REROUTE', 'GROUP', 'GROUP_INPUT', 'GROUP_OUTPUT', 'FRAME', 'OUTPUT_MATERIAL', 'OUTPUT_WORLD',
              'OUTPUT_LIGHT', 'OUTPUT_AOV'}
# Volume shaders go through the medium export (export/material.py volume_keywords); the World's
# Background and its environment through export/world.py.
VOLUME = {'PRINCIPLED_VOLUME', 'VOLUME_SCATTER', 'VOLUME_ABSORPTION'}
WORLD = {'BACKGROUND', 'TEX_ENVIRONMENT', 'MAPPING', 'TEX_COORD'}


# Nodes the compiler takes with a mode it renders otherwise (and warns about).
UNSUPPORTED_MODE = {'TEX_SKY': lambda node: node.sky_type == 'HOSEK_WILKIE'}


def supported(node, in_world):
    t = node.type
    if t in UNSUPPORTED_MODE and UNSUPPORTED_MODE[t](node):
        return False
    if t in STRUCTURAL or t in nodes.VALUE_NODES or t in nodes.SHADER_NODES or t in VOLUME:
        return True
    if t in nodes.CYCLES_DROPS:  # rendered as Cycles renders them (their links dropped)
        return True
    return in_world and t in WORLD


def walk(tree, where, in_world, seen, rows):
    for node in tree.nodes:
        if node.type == 'GROUP' and node.node_tree is not None and node.node_tree.name not in seen:
            seen.add(node.node_tree.name)
            walk(node.node_tree, "%s > group '%s'" % (where, node.node_tree.name), in_world, seen, rows)
        rows.append((where, node.name, node.bl_idname, supported(node, in_world)))


def main():
    show_all = "--all" in (sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    rows = []
    seen = set()
    for mat in bpy.data.materials:
        if mat.use_nodes and mat.node_tree is not None:
            walk(mat.node_tree, "Material '%s'" % mat.name, False, seen, rows)
    for world in bpy.data.worlds:
        if world.use_nodes and world.node_tree is not None:
            walk(world.node_tree, "World '%s'" % world.name, True, seen, rows)
    missing = [r for r in rows if not r[3]]
    print("Lantern node coverage of %s: %d nodes, %d not supported" % (bpy.data.filepath or "(unsaved)",
                                                                       len(rows), len(missing)))
    for where, name, idname, ok in rows if show_all else missing:
        print("  %-13s %s: '%s' (%s)" % ("supported" if ok else "NOT SUPPORTED", where, name, idname))
    kinds = sorted({r[2] for r in missing})
    if kinds:
        print("Unsupported node types: %s" % ", ".join(kinds))


if __name__ == "__main__":
    main()
