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
