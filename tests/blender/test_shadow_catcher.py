"""Shadow catcher agrees with Cycles 3.4 (issue 16; scenes: shadow_catcher): Object.is_shadow_catcher
with Film > Transparent off and on, Combined (the matte, its shadow approximated into alpha or over
the world behind, as Cycles with the Shadow Catcher pass off) and, with the pass on, Combined (the
catcher left transparent) and the Shadow Catcher pass. test_agreement.py's rule (per 16 x 16 tile
and RGB channel, alpha standing in for the three channels, and the image means), path tracing."""
import numpy as np
import pytest

import build_scenes
import render_utils as ru


@pytest.mark.parametrize("film_transparent,catcher_pass", [(False, False), (True, False), (False, True)])
def test_shadow_catcher_agrees_with_cycles(film_transparent, catcher_pass, scene_factory, outdir):
    runs = {}
    for engine in (ru.CYCLES, ru.LANTERN):
        scene = scene_factory("shadow_catcher")
        scene.render.film_transparent = film_transparent
        scene.view_layers[0].cycles.use_pass_shadow_catcher = catcher_pass
        runs[engine] = [ru.render(scene, engine, build_scenes.SCENES["shadow_catcher"][2], seed=s) for s in (0, 1)]
    name = "shadow_catcher_%s%s" % ("transparent" if film_transparent else "opaque", "_pass" if catcher_pass else "")
    images = {"": lambda r: r.combined[..., :3], "_alpha": lambda r: np.repeat(r.combined[..., 3:4], 3, axis=-1)}
    if catcher_pass:
        images["_pass"] = lambda r: r["Shadow Catcher"][..., :3]
        # The cube's shadow darkens the pass: it must fall below 1 somewhere in both engines.
        assert min(float(r["Shadow Catcher"][..., 0].min()) for r in runs[ru.CYCLES]) < 0.7
    for suffix, get in images.items():
        report, _ = ru.agreement_report(name + suffix, [get(r) for r in runs[ru.LANTERN]],
                                        [get(r) for r in runs[ru.CYCLES]], outdir, 16, 1e-5)
        assert report == "", report
