"""Holdout agrees with Cycles 3.4 (issue 16): the Holdout closure, Object.is_holdout and a holdout
collection (scenes: holdout), with Film > Transparent off and on. RGB and alpha each by
test_agreement.py's rule (per 16 x 16 tile and RGB channel, alpha standing in for the three
channels, and the image means), path tracing; tests/native/test_holdout.cpp checks the exact
values of every integrator, BDPT's light tracing included."""
import numpy as np
import pytest

import build_scenes
import render_utils as ru


@pytest.mark.parametrize("film_transparent", [False, True])
def test_holdout_agrees_with_cycles(film_transparent, scene_factory, outdir):
    runs = {}
    for engine in (ru.CYCLES, ru.LANTERN):
        scene = scene_factory("holdout")
        scene.render.film_transparent = film_transparent
        runs[engine] = [ru.render(scene, engine, build_scenes.SCENES["holdout"][2], seed=s).combined for s in (0, 1)]
    alpha = {e: [np.repeat(img[..., 3:4], 3, axis=-1) for img in r] for e, r in runs.items()}
    # The holdouts cover part of the image: alpha must differ from 1 there in both engines.
    assert (0.5 * sum(alpha[ru.CYCLES])[..., 0] < 0.5).mean() > 0.05
    name = "holdout_%s" % ("transparent" if film_transparent else "opaque")
    report, _ = ru.agreement_report(name, runs[ru.LANTERN], runs[ru.CYCLES], outdir, 16, 1e-5)
    assert report == "", report
    report, _ = ru.agreement_report(name + "_alpha", alpha[ru.LANTERN], alpha[ru.CYCLES], outdir, 16, 1e-5)
    assert report == "", report


def test_holdout_toggled_between_frames_exports_the_scene_anew(scene_factory, tmp_path):
    """Persistent Data keeps the core scene between frames (scene_sync.py): an object that becomes
    a holdout there is added anew, so frame 2 holds the cube out (alpha 0 at its centre)."""
    scene = scene_factory("holdout")
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    cube = scene.objects["HoldoutCube"]
    cube.is_holdout = False
    cube.keyframe_insert("is_holdout", frame=1)
    cube.is_holdout = True
    cube.keyframe_insert("is_holdout", frame=2)
    sync = ru.render_frames_with_persistent_data(scene, str(tmp_path / "anim_"))
    assert sync["full_exports"] == 2, sync
    alphas = [ru.read_multilayer_exr(str(tmp_path / ("anim_%04d.exr" % f)))["Combined"][..., 3] for f in (1, 2)]
    assert (alphas[0] - alphas[1]).max() == 1.0  # opaque in frame 1, held out in frame 2
