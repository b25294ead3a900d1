"""The test harness itself: EXR reading, linear values, and the tile statistics' false-alarm rate."""
import math
import os

import numpy as np

import bpy
import build_scenes as bs
import render_utils as ru


def test_exr_reader_agrees_with_blenders_loader(scene_factory, tmp_path):
    scene = scene_factory("sun_world")
    multi = ru.render(scene, ru.CYCLES, 8, seed=0, outdir=str(tmp_path), keep=True)
    # The same Render Result as a plain RGBA float EXR, read by both readers.
    ru._exr_settings(scene, multilayer=False)
    plain = os.path.join(str(tmp_path), "plain.exr")
    bpy.data.images["Render Result"].save_render(plain, scene=scene)
    ours = ru.read_multilayer_exr(plain)["Combined"]
    blenders = ru.load_image_pixels(plain)
    assert ours.shape == blenders.shape == (96, 96, 4)
    assert np.array_equal(ours, blenders)
    assert np.array_equal(ours, multi.combined)
    assert ours[..., :3].max() > 1.0 or ours[..., :3].mean() > 0.1  # not an empty image


def test_exr_holds_scene_linear_values_whatever_the_view_transform():
    bs.reset_file()
    scene = bs.new_scene("linear", (16, 16), 4)
    scene.view_settings.view_transform = "Filmic"
    scene.view_settings.look = "High Contrast"
    scene.view_settings.exposure = 1.5
    colour, strength = (0.2, 0.5, 1.0), 2.5
    plane = bs.add_object(scene, "Plane", bs.mesh_plane("Plane", 10.0))
    bs.assign(plane, bs._bsdf_material("Emit", "ShaderNodeEmission", colour, Strength=strength))
    bs.add_camera(scene, (0, 0, 1), (0, 0, 0))
    img = ru.render(scene, ru.CYCLES, 4, seed=0).combined
    assert np.allclose(img[..., :3], np.array(colour, np.float32) * strength, rtol=1e-6)
    assert np.all(img[..., 3] == 1.0)


def test_bonferroni_z():
    assert abs(ru.normal_quantile_upper(0.025) - 1.959964) < 1e-5
    assert abs(ru.bonferroni_z(1, 0.05) - 1.959964) < 1e-5
    z = ru.bonferroni_z(108)  # 6x6 tiles x 3 channels at 1e-3
    assert abs(0.5 * math.erfc(z / math.sqrt(2)) * 2 * 108 - 1e-3) < 1e-9


def test_tile_rule_false_alarm_rate_on_pure_noise():
    """Two 'engines' with the same mean and different noise levels: the agreement rule passes at
    nominal alpha = 0.05 about 95 % of the time (a loose check: the rule is calibrated)."""
    rng = np.random.default_rng(1)
    truth = rng.uniform(0.1, 2.0, (96, 96, 3))
    z = ru.normal_quantile_upper(0.025)
    fails = trials = 0
    for _ in range(40):
        runs = [truth + s * rng.standard_normal(truth.shape) for s in (0.3, 0.3, 0.8, 0.8)]
        mean_a, se2_a = ru.tile_mean_and_se2(runs[0], runs[1])
        mean_b, se2_b = ru.tile_mean_and_se2(runs[2], runs[3])
        fails += int((np.abs(mean_a - mean_b) > z * np.sqrt(se2_a + se2_b)).sum())
        trials += mean_a.size
    assert 0.035 < fails / trials < 0.065, fails / trials
