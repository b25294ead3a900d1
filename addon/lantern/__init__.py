"""Lantern: a physically based render engine for Blender with a native C++ core."""

bl_info = {
    "name": "Lantern",
    "author": "Lantern developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > Render Engine > Lantern",
    "description": "Physically based path tracer with a native C++ core",
    "category": "Render",
}

if "bpy" in locals():
    import importlib
    for _m in (properties, ui, engine, operators):  # noqa: F821 (reload support)
        importlib.reload(_m)
else:
    from . import properties, ui, engine, operators

import bpy  # noqa: E402,F401 (its name in locals() marks a reload, above)


def register():
    properties.register()
    engine.register()
    ui.register()
    operators.register()


def unregister():
    operators.unregister()
    ui.unregister()
    engine.unregister()
    properties.unregister()
