"""Shadow catcher agrees with Cycles 3.4 (issue 16; scenes: shadow_catcher): Object.is_shadow_catcher
with Film > Transparent off and on, Combined (the matte, its shadow approximated into alpha or over
the world behind, as Cycles with the Shadow Catcher pass off) and, with the pass on, Combined (the
catcher left transparent) and the Shadow Catcher pass. test_agreement.py's rule (per 16 x 16 tile
and RGB channel, alpha standing in for the three channels, and the image means), with path
tracing and bidirectional path tracing (bdpt.cpp's catcher split) against the same Cycles renders."""
import numpy as np
import pytest

import build_scenes
import render_utils as ru

_cycles_runs = {}  # (film_transparent, catcher_pass): Cycles' two seeds, shared by the integrators


def _runs(engine, film_transparent, catcher_pass, scene_factory, integrator):
    scene = scene_factory("shadow_catcher")
    scene.render.film_transparent = film_transparent
    scene.view_layers[0].cycles.use_pass_shadow_catcher = catcher_pass
    samples = build_scenes.SCENES["shadow_catcher"][2]
    # The approximate shadow is 1 - clamp(average(pass)): a clamp of a per-pixel ratio of means, whose
    # mean grows darker with the pass's per-pixel noise. BDPT's pass is noisier per sample here (its
    # light subpaths find the cube's bounce light; per-pixel sd 0.0187 against Cycles' 0.0141 at 128
    # samples: 0.0012 against 0.0009 of darkening from the clamp), so it renders twice the samples
    # (sd 0.013) for the comparison to test the estimators rather than their noise.
    if integrator == "BIDIRECTIONAL":
        samples *= 2
    return [ru.render(scene, engine, samples, seed=s, integrator=integrator) for s in (0, 1)]


@pytest.mark.parametrize("integrator", ["PATH", "BIDIRECTIONAL"])
@pytest.mark.parametrize("film_transparent,catcher_pass", [(False, False), (True, False), (False, True)])
def test_shadow_catcher_agrees_with_cycles(film_transparent, catcher_pass, integrator, scene_factory, outdir):
    key = (film_transparent, catcher_pass)
    if key not in _cycles_runs:
        _cycles_runs[key] = _runs(ru.CYCLES, film_transparent, catcher_pass, scene_factory, "PATH")
    runs = {ru.CYCLES: _cycles_runs[key],
            ru.LANTERN: _runs(ru.LANTERN, film_transparent, catcher_pass, scene_factory, integrator)}
    name = "shadow_catcher_%s%s_%s" % ("transparent" if film_transparent else "opaque",
                                       "_pass" if catcher_pass else "", integrator.lower())
    images = {"": lambda r: r.combined[..., :3], "_alpha": lambda r: np.repeat(r.combined[..., 3:4], 3, axis=-1)}
    if catcher_pass:
        images["_pass"] = lambda r: r["Shadow Catcher"][..., :3]
        # The cube's shadow darkens the pass: it must fall below 1 somewhere in both engines.
        for engine in runs:
            assert min(float(r["Shadow Catcher"][..., 0].min()) for r in runs[engine]) < 0.7, engine
    for suffix, get in images.items():
        report, _ = ru.agreement_report(name + suffix, [get(r) for r in runs[ru.LANTERN]],
                                        [get(r) for r in runs[ru.CYCLES]], outdir, 16, 1e-5)
        assert report == "", report
