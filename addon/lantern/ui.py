"""Lantern's panels, laid out like Cycles', and Lantern's entry in Blender's standard panels."""

import bpy
from bpy.props import EnumProperty
from bpy.types import Menu, Operator, Panel

from . import core
from .properties import PRESETS, apply_preset

ENGINE = 'LANTERN'


class LanternButtonsPanel:
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


# ---- presets -------------------------------------------------------------------------------------

class LANTERN_MT_presets(Menu):
    """Lantern's built-in presets (properties.PRESETS), like Cycles' sampling presets menu."""
    bl_label = "Presets"

    def draw(self, context):
        layout = self.layout
        for key, (label, description, _values) in PRESETS.items():
            op = layout.operator("lantern.apply_preset", text=label)
            op.preset = key


class LANTERN_OT_apply_preset(Operator):
    """Set samples, bounces and clamping for a speed/accuracy trade"""
    bl_idname = "lantern.apply_preset"
    bl_label = "Apply Lantern Preset"
    bl_options = {'REGISTER', 'UNDO'}

    preset: EnumProperty(items=[(k, v[0], v[1]) for k, v in PRESETS.items()])

    @classmethod
    def description(cls, context, properties):
        return PRESETS[properties.preset][1]

    def execute(self, context):
        apply_preset(context.scene.lantern, self.preset)
        return {'FINISHED'}


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


# ---- render properties ---------------------------------------------------------------------------

class LANTERN_RENDER_PT_sampling(LanternButtonsPanel, Panel):
    bl_label = "Sampling"

    def draw_header_preset(self, context):
        self.layout.menu("LANTERN_MT_presets", text="", icon='PRESET')

    def draw(self, context):
        _split(self.layout).prop(context.scene.lantern, "integrator")


class LANTERN_RENDER_PT_sampling_viewport(LanternButtonsPanel, Panel):
    bl_label = "Viewport"
    bl_parent_id = "LANTERN_RENDER_PT_sampling"

    def draw(self, context):
        col = _split(self.layout).column()
        col.prop(context.scene.lantern, "viewport_samples", text="Samples")
        col.prop(context.scene.lantern, "viewport_integrator", text="Integrator")


def _denoise_panel(name, parent, use, doc, start_sample=None):
    """Cycles' Sampling > Viewport or Render > Denoise: the toggle `use` in the header, the
    denoiser and (the viewport's) its start sample below."""
    def draw_header(self, context):
        self.layout.prop(context.scene.lantern, use, text="")

    def draw(self, context):
        col = _split(self.layout).column()
        col.active = getattr(context.scene.lantern, use)
        col.label(text="Denoiser: Lantern NFOR (CPU)")
        if start_sample:
            col.prop(context.scene.lantern, start_sample, text="Start Sample")

    return type(name, (LanternButtonsPanel, Panel), dict(
        __doc__=doc, bl_label="Denoise", bl_parent_id=parent, bl_options={'DEFAULT_CLOSED'},
        draw_header=draw_header, draw=draw))


LANTERN_RENDER_PT_sampling_viewport_denoise = _denoise_panel(
    "LANTERN_RENDER_PT_sampling_viewport_denoise", "LANTERN_RENDER_PT_sampling_viewport",
    "use_preview_denoising", "Cycles' Sampling > Viewport > Denoise with its Start Sample.",
    start_sample="preview_denoising_start_sample")


class LANTERN_RENDER_PT_sampling_render(LanternButtonsPanel, Panel):
    bl_label = "Render"
    bl_parent_id = "LANTERN_RENDER_PT_sampling"

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.lantern
        adaptive = settings.noise_target > 0
        # As Cycles' Render sub-panel: the noise target, then max/min samples, then the time limit.
        layout.prop(settings, "noise_target")
        col = layout.column(align=True)
        col.prop(settings, "samples", text="Max Samples" if adaptive else "Samples")
        sub = col.column(align=True)
        sub.active = adaptive
        sub.prop(settings, "min_samples")
        layout.prop(settings, "time_limit")
        sub = layout.column()
        sub.active = adaptive
        sub.prop(settings, "adaptive")


LANTERN_RENDER_PT_sampling_render_denoise = _denoise_panel(
    "LANTERN_RENDER_PT_sampling_render_denoise", "LANTERN_RENDER_PT_sampling_render",
    "use_denoising", "Cycles' Sampling > Render > Denoise (Lantern's denoiser).")


class LANTERN_RENDER_PT_sampling_bidirectional(LanternButtonsPanel, Panel):
    bl_label = "Bidirectional"
    bl_parent_id = "LANTERN_RENDER_PT_sampling"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.scene.lantern.integrator == 'BIDIRECTIONAL'

    def draw(self, context):
        settings = context.scene.lantern
        col = _split(self.layout).column(align=True)
        col.prop(settings, "max_camera_length", text="Max Camera Length")
        col.prop(settings, "max_light_length", text="Max Light Length")
        col = self.layout.column()
        col.prop(settings, "mis_heuristic")
        col.prop(settings, "strategy_view_depth")


class LANTERN_RENDER_PT_sampling_advanced(LanternButtonsPanel, Panel):
    bl_label = "Advanced"
    bl_parent_id = "LANTERN_RENDER_PT_sampling"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        col = _split(self.layout).column(align=True)
        col.prop(context.scene.lantern, "sample_pattern")
        row = col.row(align=True)
        row.prop(context.scene.lantern, "seed")
        row.prop(context.scene.lantern, "use_animated_seed", text="", icon='TIME')
        col.prop(context.scene.lantern, "sample_offset")


class LANTERN_RENDER_PT_light_paths(LanternButtonsPanel, Panel):
    bl_label = "Light Paths"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        pass


class LANTERN_RENDER_PT_light_paths_max_bounces(LanternButtonsPanel, Panel):
    bl_label = "Max Bounces"
    bl_parent_id = "LANTERN_RENDER_PT_light_paths"

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.lantern

        col = layout.column(align=True)
        col.prop(settings, "max_bounces", text="Total")

        col = layout.column(align=True)
        col.prop(settings, "diffuse_bounces", text="Diffuse")
        col.prop(settings, "glossy_bounces", text="Glossy")
        col.prop(settings, "transmission_bounces", text="Transmission")
        col.prop(settings, "volume_bounces", text="Volume")

        col = layout.column(align=True)
        col.prop(settings, "transparent_bounces", text="Transparent")


class LANTERN_RENDER_PT_light_paths_clamping(LanternButtonsPanel, Panel):
    bl_label = "Clamping"
    bl_parent_id = "LANTERN_RENDER_PT_light_paths"

    def draw(self, context):
        settings = context.scene.lantern
        col = _split(self.layout).column(align=True)
        col.prop(settings, "clamp_direct", text="Direct Light")
        col.prop(settings, "clamp_indirect", text="Indirect Light")


class LANTERN_RENDER_PT_volumes(LanternButtonsPanel, Panel):
    bl_label = "Volumes"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        settings = context.scene.lantern
        col = _split(self.layout).column(align=True)
        col.prop(settings, "volume_estimator", text="Estimator")
        sub = col.column(align=True)
        sub.active = settings.volume_estimator == 'RAY_MARCHING' or settings.integrator == 'VOLUME_DEBUG'
        sub.prop(settings, "volume_step", text="Step Size")


class LANTERN_RENDER_PT_motion_blur(LanternButtonsPanel, Panel):
    """Blender's and Cycles' motion blur settings, which Lantern renders as Cycles (final renders
    only; export/motion.py)."""
    bl_label = "Motion Blur"
    bl_options = {'DEFAULT_CLOSED'}

    def draw_header(self, context):
        self.layout.prop(context.scene.render, "use_motion_blur", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        rd = context.scene.render
        layout.active = rd.use_motion_blur
        col = layout.column()
        cscene = getattr(context.scene, "cycles", None)
        if cscene is not None and hasattr(cscene, "motion_blur_position"):
            col.prop(cscene, "motion_blur_position", text="Position")
        col.prop(rd, "motion_blur_shutter")
        col.label(text="Rolling shutter and shutter curves are not supported", icon='INFO')


class LANTERN_OBJECT_PT_motion_blur(LanternButtonsPanel, Panel):
    """Cycles' per-object motion blur settings (the Cycles add-on's obj.cycles)."""
    bl_label = "Motion Blur"
    bl_context = "object"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        ob = context.object
        return super().poll(context) and ob is not None and getattr(ob, "cycles", None) is not None and \
            ob.type in {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'CAMERA'}

    def draw_header(self, context):
        self.layout.active = context.scene.render.use_motion_blur
        self.layout.prop(context.object.cycles, "use_motion_blur", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        cob = context.object.cycles
        layout.active = context.scene.render.use_motion_blur and cob.use_motion_blur
        col = layout.column()
        col.prop(cob, "motion_steps", text="Steps")
        if context.object.type != 'CAMERA':
            col.prop(cob, "use_deform_motion", text="Deformation")


class LANTERN_RENDER_PT_film(LanternButtonsPanel, Panel):
    bl_label = "Film"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        pass


class LANTERN_RENDER_PT_film_transparency(LanternButtonsPanel, Panel):
    bl_label = "Transparent"
    bl_parent_id = "LANTERN_RENDER_PT_film"

    def draw_header(self, context):
        self.layout.prop(context.scene.render, "film_transparent", text="")

    def draw(self, context):
        layout = _split(self.layout)
        layout.active = context.scene.render.film_transparent
        layout.label(text="Background: alpha 0, still lit")


class LANTERN_RENDER_PT_film_pixel_filter(LanternButtonsPanel, Panel):
    bl_label = "Pixel Filter"
    bl_parent_id = "LANTERN_RENDER_PT_film"

    def draw(self, context):
        layout = _split(self.layout)
        # Lantern uses Cycles' pixel filter settings so both engines render a scene alike.
        cscene = getattr(context.scene, "cycles", None)
        if cscene is None:
            try:  # the core's default filter is used
                d = core.default_settings()
                name = "%s, %g px" % (core.enum_name("lt_filter", d.filter).replace("_", "-").title(), d.filter_width)
            except core.LanternError:  # no library: nothing renders anyway
                name = "The core's default"
            layout.label(text="%s (enable Cycles to change it)" % name)
            return
        col = layout.column()
        col.prop(cscene, "pixel_filter_type", text="Type")
        if cscene.pixel_filter_type != 'BOX':
            col.prop(cscene, "filter_width", text="Width")


class LANTERN_RENDER_PT_performance(LanternButtonsPanel, Panel):
    bl_label = "Performance"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        pass


class LANTERN_RENDER_PT_performance_threads(LanternButtonsPanel, Panel):
    bl_label = "Threads"
    bl_parent_id = "LANTERN_RENDER_PT_performance"

    def draw(self, context):
        # Blender's own setting (as Cycles shows it), which `blender -t N` sets.
        layout = _split(self.layout)
        rd = context.scene.render
        layout.prop(rd, "threads_mode")
        sub = layout.column(align=True)
        sub.enabled = rd.threads_mode == 'FIXED'
        sub.prop(rd, "threads")


class LANTERN_RENDER_PT_performance_final_render(LanternButtonsPanel, Panel):
    bl_label = "Final Render"
    bl_parent_id = "LANTERN_RENDER_PT_performance"

    def draw(self, context):
        # Blender's own setting, as Cycles shows it: the scene stays between animation frames.
        _split(self.layout).prop(context.scene.render, "use_persistent_data", text="Persistent Data")


# ---- view layer --------------------------------------------------------------------------------

class LANTERN_VIEWLAYER_PT_passes(LanternButtonsPanel, Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        view_layer = context.view_layer

        col = layout.column(heading="Include", align=True)
        col.prop(view_layer, "use_pass_combined")
        col.prop(view_layer, "use_pass_z")
        col.prop(view_layer, "use_pass_normal")
        col.prop(view_layer, "lantern_extra_passes")
        col.prop(view_layer, "lantern_denoising_store_passes")


class LANTERN_VIEWLAYER_PT_passes_data(LanternButtonsPanel, Panel):
    bl_label = "Data"
    bl_context = "view_layer"
    bl_parent_id = "LANTERN_VIEWLAYER_PT_passes"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        view_layer = context.view_layer
        col = layout.column(heading="Include", align=True)
        col.prop(view_layer, "use_pass_position")
        sub = col.column()
        sub.active = not context.scene.render.use_motion_blur  # zero with motion blur, as Cycles'
        sub.prop(view_layer, "use_pass_vector")
        col.prop(view_layer, "use_pass_uv")
        col.prop(view_layer, "use_pass_mist")
        col = layout.column(heading="Indexes", align=True)
        col.prop(view_layer, "use_pass_object_index")
        col.prop(view_layer, "use_pass_material_index")


class LANTERN_VIEWLAYER_PT_passes_light(LanternButtonsPanel, Panel):
    bl_label = "Light"
    bl_context = "view_layer"
    bl_parent_id = "LANTERN_VIEWLAYER_PT_passes"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        view_layer = context.view_layer
        for heading, kind in (("Diffuse", "diffuse"), ("Glossy", "glossy"), ("Transmission", "transmission")):
            col = layout.column(heading=heading, align=True)
            col.prop(view_layer, "use_pass_%s_direct" % kind, text="Direct")
            col.prop(view_layer, "use_pass_%s_indirect" % kind, text="Indirect")
            col.prop(view_layer, "use_pass_%s_color" % kind, text="Color")
        cycles_view_layer = getattr(view_layer, "cycles", None)
        if cycles_view_layer is not None:  # the Volume toggles are the Cycles add-on's
            col = layout.column(heading="Volume", align=True)
            col.prop(cycles_view_layer, "use_pass_volume_direct", text="Direct")
            col.prop(cycles_view_layer, "use_pass_volume_indirect", text="Indirect")
        col = layout.column(heading="Other", align=True)
        col.prop(view_layer, "use_pass_emit", text="Emission")
        col.prop(view_layer, "use_pass_environment")
        col.prop(view_layer, "use_pass_ambient_occlusion", text="Ambient Occlusion")
        if cycles_view_layer is not None:  # Cycles' toggle; off: Combined approximates the shadows
            col.prop(cycles_view_layer, "use_pass_shadow_catcher")


class LANTERN_VIEWLAYER_PT_passes_crypto(LanternButtonsPanel, Panel):
    """Cycles' View Layer > Passes > Cryptomatte (properties_view_layer.py's ViewLayerCryptomattePanel)."""
    bl_label = "Cryptomatte"
    bl_context = "view_layer"
    bl_parent_id = "LANTERN_VIEWLAYER_PT_passes"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        view_layer = context.view_layer
        col = layout.column(heading="Include", align=True)
        col.prop(view_layer, "use_pass_cryptomatte_object", text="Object")
        col.prop(view_layer, "use_pass_cryptomatte_material", text="Material")
        col.prop(view_layer, "use_pass_cryptomatte_asset", text="Asset")
        col = layout.column()
        col.prop(view_layer, "pass_cryptomatte_depth", text="Levels")


# ---- object, light, material, world ----------------------------------------------------------

class LANTERN_OBJECT_PT_visibility(LanternButtonsPanel, Panel):
    bl_label = "Visibility"
    bl_context = "object"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.object is not None

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        ob = context.object

        col = layout.column(heading="Show In")
        col.prop(ob, "hide_viewport", text="Viewports", invert_checkbox=True, toggle=False)
        col.prop(ob, "hide_render", text="Renders", invert_checkbox=True, toggle=False)

        if ob.type in {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'LIGHT', 'CURVES',
                       'POINTCLOUD', 'VOLUME'}:
            col = layout.column(heading="Ray Visibility")
            col.prop(ob, "visible_camera", text="Camera")
            col.prop(ob, "visible_diffuse", text="Diffuse")
            col.prop(ob, "visible_glossy", text="Glossy")
            col.prop(ob, "visible_transmission", text="Transmission")
            if ob.type != 'LIGHT':
                col.prop(ob, "visible_shadow", text="Shadow")

        if ob.type in {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'CURVES', 'POINTCLOUD', 'VOLUME'}:
            col = layout.column(heading="Mask")  # as Cycles' Object > Visibility > Mask
            col.prop(ob, "is_shadow_catcher")
            col.prop(ob, "is_holdout")


class LANTERN_LIGHT_PT_light(LanternButtonsPanel, Panel):
    bl_label = "Light"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return context.light is not None and super().poll(context)

    def draw(self, context):
        layout = self.layout
        light = context.light

        layout.row().prop(light, "type", expand=True)
        layout.use_property_split = True

        col = layout.column()
        col.prop(light, "color")
        col.prop(light, "energy")
        col.separator()

        if light.type in {'POINT', 'SPOT'}:
            col.prop(light, "shadow_soft_size", text="Radius")
        elif light.type == 'SUN':
            col.prop(light, "angle")
        elif light.type == 'AREA':
            col.prop(light, "shape", text="Shape")
            sub = col.column(align=True)
            if light.shape in {'SQUARE', 'DISK'}:
                sub.prop(light, "size")
            else:
                sub.prop(light, "size", text="Size X")
                sub.prop(light, "size_y", text="Y")
            col.prop(light, "spread")


def _node_view(layout, id_data, input_name, fallback_prop):
    if not id_data.use_nodes:
        layout.prop(id_data, "use_nodes", icon='NODETREE')
        layout.prop(id_data, fallback_prop)
        return
    ntree = id_data.node_tree
    node = ntree.get_output_node('CYCLES')  # Lantern reads the output Cycles would use
    if node is None:
        layout.label(text="No output node")
        return
    socket = node.inputs.get(input_name)
    if socket is None:
        layout.label(text="Incompatible output node")
    else:
        layout.template_node_view(ntree, node, socket)


class LANTERN_CAMERA_PT_panorama(Panel):
    """A panoramic camera's projection (Cycles' camera settings, which Blender's Lens panel draws
    only under Cycles), under the Lens panel."""
    bl_label = "Panorama"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "data"
    bl_parent_id = "DATA_PT_lens"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES and context.camera and context.camera.type == 'PANO'

    def draw(self, context):
        layout = _split(self.layout)
        ccam = getattr(context.camera, "cycles", None)
        if ccam is None or not hasattr(ccam, "panorama_type"):
            layout.label(text="Panorama settings need the Cycles add-on", icon='ERROR')
            return
        layout.prop(ccam, "panorama_type")
        col = layout.column()
        if ccam.panorama_type == 'FISHEYE_EQUIDISTANT':
            col.prop(ccam, "fisheye_fov")
        elif ccam.panorama_type == 'FISHEYE_EQUISOLID':
            col.prop(ccam, "fisheye_lens", text="Lens")
            col.prop(ccam, "fisheye_fov")
        elif ccam.panorama_type == 'EQUIRECTANGULAR':
            sub = col.column(align=True)
            sub.prop(ccam, "latitude_min", text="Latitude Min")
            sub.prop(ccam, "latitude_max", text="Max")
            sub = col.column(align=True)
            sub.prop(ccam, "longitude_min", text="Longitude Min")
            sub.prop(ccam, "longitude_max", text="Max")
        elif ccam.panorama_type == 'FISHEYE_LENS_POLYNOMIAL':
            col.prop(ccam, "fisheye_fov")
            for i in range(5):
                col.prop(ccam, "fisheye_polynomial_k%d" % i, text="K%d" % i)
        elif ccam.panorama_type not in ('MIRRORBALL', 'EQUIANGULAR_CUBEMAP_FACE'):
            col.label(text="Not supported by Lantern: rendered as perspective", icon='ERROR')


class LANTERN_MATERIAL_PT_surface(LanternButtonsPanel, Panel):
    bl_label = "Surface"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        mat = context.material
        return mat is not None and not mat.grease_pencil and super().poll(context)

    def draw(self, context):
        self.layout.use_property_split = True
        _node_view(self.layout, context.material, "Surface", "diffuse_color")


class LANTERN_WORLD_PT_surface(LanternButtonsPanel, Panel):
    bl_label = "Surface"
    bl_context = "world"

    @classmethod
    def poll(cls, context):
        return context.world is not None and super().poll(context)

    def draw(self, context):
        self.layout.use_property_split = True
        _node_view(self.layout, context.world, "Surface", "color")


class LANTERN_WORLD_PT_ray_visibility(LanternButtonsPanel, Panel):
    bl_label = "Ray Visibility"
    bl_context = "world"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return (context.world is not None and hasattr(context.world, "cycles_visibility")
                and super().poll(context))

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(context.world.cycles_visibility, "camera")


class LANTERN_WORLD_PT_ambient_occlusion(LanternButtonsPanel, Panel):
    """The AO pass's ray length (World > Light Settings > Distance; Cycles shows it in its Fast GI
    panel, which Lantern has not), when a view layer asks for the pass."""
    bl_label = "Ambient Occlusion"
    bl_context = "world"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return (context.world is not None and super().poll(context)
                and any(v.use_pass_ambient_occlusion for v in context.scene.view_layers))

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(context.world.light_settings, "distance", text="AO Distance")


class LANTERN_WORLD_PT_settings(LanternButtonsPanel, Panel):
    """Cycles' world importance-sampling map (the core bakes the world's nodes into it): its
    resolution trades commit time and memory against noise from small bright spots."""
    bl_label = "Settings"
    bl_context = "world"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return context.world is not None and hasattr(context.world, "cycles") and super().poll(context)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.world.cycles
        col = layout.column()
        col.prop(settings, "sampling_method", text="Sampling")
        sub = col.column()
        sub.active = settings.sampling_method == 'MANUAL'
        sub.prop(settings, "sample_map_resolution")


classes = (
    LANTERN_MT_presets,
    LANTERN_OT_apply_preset,
    LANTERN_RENDER_PT_sampling,
    LANTERN_RENDER_PT_sampling_viewport,
    LANTERN_RENDER_PT_sampling_render,
    LANTERN_RENDER_PT_sampling_viewport_denoise,
    LANTERN_RENDER_PT_sampling_render_denoise,
    LANTERN_RENDER_PT_sampling_bidirectional,
    LANTERN_RENDER_PT_sampling_advanced,
    LANTERN_RENDER_PT_light_paths,
    LANTERN_RENDER_PT_light_paths_max_bounces,
    LANTERN_RENDER_PT_light_paths_clamping,
    LANTERN_RENDER_PT_volumes,
    LANTERN_RENDER_PT_motion_blur,
    LANTERN_RENDER_PT_film,
    LANTERN_RENDER_PT_film_transparency,
    LANTERN_RENDER_PT_film_pixel_filter,
    LANTERN_RENDER_PT_performance,
    LANTERN_RENDER_PT_performance_threads,
    LANTERN_RENDER_PT_performance_final_render,
    LANTERN_VIEWLAYER_PT_passes,
    LANTERN_VIEWLAYER_PT_passes_data,
    LANTERN_VIEWLAYER_PT_passes_light,
    LANTERN_VIEWLAYER_PT_passes_crypto,
    LANTERN_OBJECT_PT_visibility,
    LANTERN_OBJECT_PT_motion_blur,
    LANTERN_LIGHT_PT_light,
    LANTERN_CAMERA_PT_panorama,
    LANTERN_MATERIAL_PT_surface,
    LANTERN_WORLD_PT_surface,
    LANTERN_WORLD_PT_ray_visibility,
    LANTERN_WORLD_PT_settings,
    LANTERN_WORLD_PT_ambient_occlusion,
)


# ---- standard panels ---------------------------------------------------------------------------

# Standard panels for 'BLENDER_RENDER' that would mislead under Lantern (Lantern has its own).
_EXCLUDED_PANELS = {
    "DATA_PT_light",          # only the type: LANTERN_LIGHT_PT_light replaces it
    "DATA_PT_area",           # in LANTERN_LIGHT_PT_light
    "DATA_PT_falloff_curve",  # light falloff curves are not used by Lantern
    "OBJECT_PT_visibility",   # LANTERN_OBJECT_PT_visibility adds ray visibility
    "DATA_PT_preview",
}
# Engine-agnostic panels that do not list 'BLENDER_RENDER'.
_EXTRA_PANELS = {
    "EEVEE_MATERIAL_PT_context_material",  # material slots
    "DATA_PT_spot",                         # spot size and blend
    "RENDER_PT_color_management",
    "MATERIAL_PT_preview",                  # Lantern renders material previews (bl_use_preview)
    "DATA_PT_camera_dof",                   # depth of field, as Cycles renders it
    "DATA_PT_camera_dof_aperture",
}

_patched = []


def _standard_panels():
    for name in dir(bpy.types):
        cls = getattr(bpy.types, name, None)
        if not isinstance(cls, type) or not issubclass(cls, Panel) or name.startswith("LANTERN_"):
            continue
        if getattr(cls, "bl_space_type", None) != 'PROPERTIES':
            continue
        # Only a class's own set: an inherited one would enable every sibling panel too.
        engines = cls.__dict__.get("COMPAT_ENGINES")
        if not isinstance(engines, set):
            continue
        if name in _EXTRA_PANELS or ('BLENDER_RENDER' in engines and name not in _EXCLUDED_PANELS):
            yield cls


def register():
    for c in classes:
        bpy.utils.register_class(c)
    for panel in _standard_panels():
        if ENGINE not in panel.COMPAT_ENGINES:
            panel.COMPAT_ENGINES.add(ENGINE)
            _patched.append(panel)


def unregister():
    for panel in _patched:
        panel.COMPAT_ENGINES.discard(ENGINE)
    _patched.clear()
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
