"""Lantern's render settings, stored on the scene as scene.lantern."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty


# Built-in presets: (label, tooltip, values). Bounce limits and clamping trade accuracy (energy
# of long paths, bias from clamping) for speed; samples trade noise for time.
PRESETS = {
    'PREVIEW': ("Preview", "Fast and noisy, biased: few samples, short paths, indirect light "
                           "clamped at 10 (for looking around a scene)",
                dict(samples=16, viewport_samples=8, max_bounces=4, diffuse_bounces=2,
                     glossy_bounces=2, transmission_bounces=4, transparent_bounces=4,
                     volume_bounces=0, clamp_direct=0.0, clamp_indirect=10.0)),
    'FINAL': ("Final", "Cycles' defaults: 256 samples, Cycles' bounce limits and its indirect "
                       "clamp of 10 (slightly biased, few fireflies)",
              dict(samples=256, viewport_samples=32, max_bounces=12, diffuse_bounces=4,
                   glossy_bounces=4, transmission_bounces=12, transparent_bounces=8,
                   volume_bounces=0, clamp_direct=0.0, clamp_indirect=10.0)),
    'REFERENCE': ("Reference", "Slow and unbiased: 4096 samples, long paths and no clamping (for "
                               "ground truth and comparisons)",
                  dict(samples=4096, viewport_samples=64, max_bounces=64, diffuse_bounces=64,
                       glossy_bounces=64, transmission_bounces=64, transparent_bounces=64,
                       volume_bounces=16, clamp_direct=0.0, clamp_indirect=0.0)),
}


def apply_preset(settings, key):
    for name, value in PRESETS[key][2].items():
        setattr(settings, name, value)


# Blender declares properties when the add-on registers, before (and without) the native library,
# so the defaults below are written out; they are the core's (lt_render_settings_default) and the
# enum identifiers are the core's enum names (lt_integrator, lt_mis, lt_volume_estimator,
# lt_sample_pattern without their prefix), which engine.render_settings passes through core.enum_value. test_engine's
# test_properties_match_core holds both to the library.
class LanternRenderSettings(bpy.types.PropertyGroup):
    samples: IntProperty(
        name="Samples",
        description="Samples per pixel: more samples give less noise and take proportionally "
                    "longer",
        default=64, min=1, max=1 << 24, soft_max=4096,
    )
    time_limit: FloatProperty(
        name="Time Limit",
        description="Stop rendering after this many seconds (the first sample pass always "
                    "completes), whatever the noise: a predictable render time for an "
                    "unpredictable noise level; 0 renders without a time limit",
        default=0.0, min=0.0, soft_max=3600.0, subtype='TIME_ABSOLUTE', unit='TIME_ABSOLUTE',
    )
    noise_target: FloatProperty(
        name="Noise Target",
        description="Stop rendering once the estimated relative error of the image (RMS noise "
                    "over the image's RMS, from two independent half images) falls to this: "
                    "halving it takes about four times as long; 0 renders the full Samples",
        default=0.0, min=0.0, max=1.0, soft_max=0.2, precision=4, subtype='FACTOR',
    )
    adaptive: BoolProperty(
        name="Adaptive Sampling",
        description="With a noise target: pixels whose own noise is already below their share of "
                    "the target stop sampling, so the time goes to the noisy ones; reaches the "
                    "target sooner, at the risk of stopping a pixel that has not yet met a rare "
                    "bright path (raise Min Samples against that)",
        default=False,
    )
    min_samples: IntProperty(
        name="Min Samples",
        description="Samples every pixel takes before the noise target and adaptive sampling are "
                    "checked: more is slower for easy scenes but safer against noise estimated "
                    "from too few samples (fireflies not yet seen)",
        default=16, min=1, max=1 << 24, soft_max=1024,
    )
    use_denoising: BoolProperty(
        name="Denoise",
        description="Denoise the rendered image (Lantern's NFOR-style denoiser on the CPU; the "
                    "image as rendered is kept as the Noisy Image pass and the status line's "
                    "error is its own). Off by default: a denoised image is no longer unbiased",
        default=False,
        update=lambda self, context: _update_render_passes(context),
    )
    viewport_samples: IntProperty(
        name="Viewport Samples",
        description="Samples per pixel the viewport refines to before it stops: more give a "
                    "cleaner preview but keep the CPU busy longer after each change",
        default=32, min=1, max=1 << 24, soft_max=4096,
    )
    viewport_integrator: EnumProperty(
        name="Viewport Integrator",
        description="The integrator the viewport previews with (F12 always uses the Integrator above): "
                    "a faster one refines the preview sooner",
        items=[
            ("FAST", "Fast Preview",
             "Volumetric path tracing in the viewport when the render is Bidirectional (several "
             "times the cost per sample; the same image where path tracing finds the light: "
             "caustics only light tracing finds, a point lamp's through sharp glass, show in "
             "the render alone); otherwise the render's integrator"),
            ("RENDER", "Same as Render", "The render's integrator, at its cost per sample"),
        ],
        default="FAST",
    )
    # Cycles' Sampling > Viewport > Denoise (scene.cycles.use_preview_denoising and
    # preview_denoising_start_sample): the core denoises the image the viewport reads while it
    # refines (lt_render_settings.denoise_start_sample).
    use_preview_denoising: BoolProperty(
        name="Viewport Denoise",
        description="Denoise the viewport's image while it refines (Lantern's NFOR-style denoiser "
                    "on the CPU): a cleaner preview sooner, at a cost of at most a quarter of the "
                    "viewport's time; the status line's error stays that of the image as rendered",
        default=False,
    )
    preview_denoising_start_sample: IntProperty(
        name="Start Sample",
        description="Sample to start denoising the preview at: earlier gives a cleaner preview "
                    "sooner, from a noise estimate of fewer samples (the denoiser needs at least 2)",
        default=1, min=0, max=1 << 24, soft_max=4096,
    )
    seed: IntProperty(
        name="Seed",
        description="Seed of the random numbers: renders with different seeds have independent "
                    "noise and can be averaged (costs nothing; the same seed repeats the same "
                    "noise exactly)",
        default=0, min=0,
    )
    use_animated_seed: BoolProperty(
        name="Animated Seed",
        description="Use a different seed for each frame, so that an animation's noise changes "
                    "from frame to frame (as Cycles' Animated Seed: the seed is hashed with the frame)",
        default=False,
    )
    sample_offset: IntProperty(
        name="Sample Offset",
        description="Number of samples to skip when starting the render: a render of samples "
                    "[offset, offset + samples) uses exactly the random numbers those samples use in "
                    "a full render, so parts rendered on several machines merge (Merge Images, "
                    "`lantern merge`) into the full render (costs nothing; parts with overlapping "
                    "ranges repeat the same noise and must not be merged)",
        default=0, min=0, max=(1 << 30) - (1 << 24),
    )
    integrator: EnumProperty(
        name="Integrator",
        description="Light transport algorithm: what it costs per sample against how fast its "
                    "noise falls in hard lighting",
        items=[
            ("PATH", "Path Tracing",
             "Unidirectional path tracing with next event estimation and multiple importance "
             "sampling: robust for most scenes"),
            ("BIDIRECTIONAL", "Bidirectional",
             "Bidirectional path tracing: also traces paths from the lights and connects them to "
             "camera paths, through participating media too; slower per sample, but converges "
             "much faster where light is hard to reach (light through gaps, caustics, small "
             "bright lights)"),
            ("VOLPATH", "Volumetric Path",
             "Path tracing through participating media (volume materials, Volume objects); the "
             "same as Path Tracing in scenes without volumes"),
            ("VOLUME_DEBUG", "Volume Debug",
             "Estimator view for the same camera rays, four half-size panels: transmittance by "
             "ray marching (top left) and ratio tracking (top right), sampled collision distance "
             "in metres by ray marching (bottom left) and delta tracking (bottom right)"),
        ],
        default="PATH",
    )
    max_camera_length: IntProperty(
        name="Max Camera Path Length",
        description="Bidirectional: vertices of the camera subpath after the camera (the total "
                    "bounce limit also applies); shorter is faster but loses long paths",
        default=64, min=1, max=1024,
    )
    max_light_length: IntProperty(
        name="Max Light Path Length",
        description="Bidirectional: vertices of the light subpath, the one on the light included. "
                    "1 makes it equal to path tracing with next event estimation; longer light "
                    "paths find caustics and hard-to-reach light at a higher cost per sample",
        default=64, min=0, max=1024,
    )
    strategy_view_depth: IntProperty(
        name="Strategy View Depth",
        description="Bidirectional: also keep the weighted contribution of every (s, t) strategy "
                    "for path depths below this, shown as a grid in the image 'Lantern Strategies' "
                    "(for debugging and teaching; costs memory per strategy image). 0 turns it off",
        default=0, min=0, max=8,
    )
    mis_heuristic: EnumProperty(
        name="MIS Heuristic",
        description="Bidirectional: how the connection strategies are weighted; all are "
                    "unbiased, they differ only in noise",
        items=[
            ("POWER", "Power", "Veach's power heuristic (exponent 2): the lowest noise in practice"),
            ("BALANCE", "Balance", "Veach's balance heuristic"),
            ("UNIFORM", "Uniform", "Every strategy weighted equally (for teaching: unbiased, but "
                                   "noisy)"),
        ],
        default="POWER",
    )
    max_bounces: IntProperty(
        name="Total",
        description="Total maximum number of bounces: fewer is faster but loses (darkens) the "
                    "light of long paths",
        default=12, min=0, max=1024,
    )
    diffuse_bounces: IntProperty(
        name="Diffuse",
        description="Maximum number of diffuse reflection bounces, bounded by the total: fewer "
                    "is faster but darkens indirect diffuse lighting",
        default=4, min=0, max=1024,
    )
    glossy_bounces: IntProperty(
        name="Glossy",
        description="Maximum number of glossy reflection bounces, bounded by the total: fewer "
                    "is faster but darkens reflections of reflections",
        default=4, min=0, max=1024,
    )
    transmission_bounces: IntProperty(
        name="Transmission",
        description="Maximum number of transmission bounces, bounded by the total: fewer is "
                    "faster but darkens what is seen through several glass surfaces",
        default=12, min=0, max=1024,
    )
    transparent_bounces: IntProperty(
        name="Transparent",
        description="Maximum number of transparent bounces (independent of the total): fewer "
                    "is faster but makes stacks of transparent surfaces opaque",
        default=8, min=0, max=1024,
    )
    clamp_direct: FloatProperty(
        name="Direct Light",
        description="Clamp the contribution of direct lighting samples to this value to reduce "
                    "fireflies, at the cost of bias (darker highlights); 0 disables clamping",
        default=0.0, min=0.0,
    )
    clamp_indirect: FloatProperty(
        name="Indirect Light",
        description="Clamp the contribution of indirect lighting samples to this value to "
                    "reduce fireflies, at the cost of bias (darker indirect light); 0 disables "
                    "clamping (Cycles defaults to 10)",
        default=0.0, min=0.0,
    )
    sample_pattern: EnumProperty(
        name="Pattern",
        description="Where each sample's random numbers come from: Sobol-Owen gives less noise at "
                    "equal samples where lighting is smooth, for a slightly higher cost per sample",
        items=[
            ("SOBOL_OWEN", "Sobol-Owen",
             "Low-discrepancy Sobol' points, Owen-scrambled per pixel and per dimension: less noise "
             "at equal samples on smooth lighting (soft shadows, skies, the pixel footprint)"),
            ("INDEPENDENT", "Independent",
             "Independent random numbers for every sample (PCG32)"),
        ],
        default="SOBOL_OWEN",
    )
    volume_estimator: EnumProperty(
        name="Volume Estimator",
        description="How heterogeneous volumes (VDB grids) are sampled, trading bias for noise; "
                    "homogeneous volumes are always exact",
        items=[
            ("RAY_MARCHING", "Ray Marching",
             "Fixed steps of the Step Size: deterministic transmittance, biased by the step"),
            ("TRACKING", "Delta/Ratio Tracking",
             "Unbiased delta tracking and ratio tracking against per-cell majorants"),
        ],
        default="TRACKING",
    )
    volume_step: FloatProperty(
        name="Step Size",
        description="Ray-marching step in world units for every Volume object; 0 uses each "
                    "object's own Step Size (Volume data > Render), or its voxel size when that "
                    "is 0. Smaller steps are less biased but slower",
        default=0.0, min=0.0, subtype='DISTANCE',
    )
    volume_bounces: IntProperty(
        name="Volume",
        description="Maximum number of volume scattering bounces (Cycles' default 0 is single "
                    "scattering: direct light only inside volumes); more is brighter, more "
                    "accurate in dense media and slower",
        default=0, min=0, max=1024,
    )


classes = (LanternRenderSettings,)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.lantern = PointerProperty(type=LanternRenderSettings)
    # A pass toggle where Blender keeps the others (View Layer > Passes), off by default as in
    # Cycles: each pass costs film memory for every pixel.
    bpy.types.ViewLayer.lantern_extra_passes = BoolProperty(
        name="Albedo, Variance, Sample Count",
        description="Also render the Albedo, Variance and Sample Count passes (each costs memory "
                    "for every pixel)",
        default=False)
    bpy.types.ViewLayer.lantern_denoising_store_passes = BoolProperty(
        name="Denoising Data",
        description="Store the denoising feature passes (Denoising Normal, Albedo and Depth, as "
                    "Cycles names them); each costs memory for every pixel",
        default=False, update=lambda self, context: _update_render_passes(context))


def _update_render_passes(context):
    """Lets Blender ask the engine for its passes again (the compositor's Render Layers node)."""
    view_layer = getattr(context, "view_layer", None)
    if view_layer is not None:
        view_layer.update_render_passes()


def unregister():
    del bpy.types.ViewLayer.lantern_denoising_store_passes
    del bpy.types.ViewLayer.lantern_extra_passes
    del bpy.types.Scene.lantern
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
