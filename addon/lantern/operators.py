"""Operators: Merge Images (sample-split parts into one render, like Cycles' Merge Images)."""

import os

import bpy
from bpy.props import CollectionProperty, StringProperty
from bpy.types import Operator, OperatorFileListElement

from . import core


class LANTERN_OT_merge_images(Operator):
    """Merge sample-split Lantern renders (EXR parts with different Sample Offsets) into the image one
    render of all their samples gives: a sample-weighted average of every pass"""
    bl_idname = "lantern.merge_images"
    bl_label = "Merge Images"
    bl_options = {'REGISTER'}

    directory: StringProperty(subtype='DIR_PATH', options={'SKIP_SAVE'})
    files: CollectionProperty(type=OperatorFileListElement, options={'SKIP_SAVE'})
    filter_glob: StringProperty(default="*.exr", options={'HIDDEN'})
    output_filepath: StringProperty(
        name="Output", subtype='FILE_PATH',
        description="Where the merged EXR goes (default: merged.exr beside the parts); nothing is "
                    "written if the parts cannot be merged")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}

    def execute(self, context):
        parts = [os.path.join(bpy.path.abspath(self.directory), f.name) for f in self.files if f.name]
        if not parts:
            self.report({'ERROR'}, "Select the EXR parts to merge")
            return {'CANCELLED'}
        out = bpy.path.abspath(self.output_filepath) if self.output_filepath else \
            os.path.join(os.path.dirname(parts[0]), "merged.exr")
        try:
            core.merge_exr(out, parts)
        except core.LanternError as e:
            self.report({'ERROR'}, str(e))
            return {'CANCELLED'}
        self.report({'INFO'}, "Merged %d parts into %s" % (len(parts), out))
        return {'FINISHED'}


def _menu(self, context):
    self.layout.operator(LANTERN_OT_merge_images.bl_idname, text="Merge Lantern Images")


def register():
    bpy.utils.register_class(LANTERN_OT_merge_images)
    bpy.types.TOPBAR_MT_render.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_render.remove(_menu)
    bpy.utils.unregister_class(LANTERN_OT_merge_images)
