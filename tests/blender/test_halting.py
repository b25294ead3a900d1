"""Halting, the error estimate and adaptive sampling, with real renders of the test scenes.

The estimate (lt_render_status.rel_error, core/film.h) claims E = sqrt(E[sum (I - R)^2] / sum R^2)
over pixels and RGB channels, R the converged image. It is measured here against a reference made
of two independent Lantern renders R1, R2 at REF_SAMPLES each (seeds unlike the tested ones):
R = (R1 + R2) / 2 still has noise, whose summed variance V_R = sum (R1 - R2)^2 / 4 is known without
the estimator under test, so the measured error is
    E_meas^2 = (sum (I - R)^2 - V_R) / (sum R^2 - V_R).
"""
import json
import os
import time

import numpy as np
import pytest

import render_utils as ru
from lantern import core, engine

HONESTY_SCENES = [("cornell_area", "PATH"), ("glossy_glass", "PATH"), ("cornell_point", "BIDIRECTIONAL")]
HONESTY_SAMPLES = (4, 16, 64, 256)
HONESTY_POOL = 64  # samples per pixel pooled over renders at each count
FACTOR = 1.5  # the bound on predicted / measured error
REF_SAMPLES = 2048
PERCENT = 50  # 96x96 scenes rendered at 48x48
_REFS = {}


def _reset_halting(scene, percent=PERCENT):
    scene.render.resolution_percentage = percent
    scene.view_layers[0].lantern_extra_passes = True  # the Sample Count pass
    lt = scene.lantern
    lt.time_limit, lt.noise_target, lt.adaptive, lt.min_samples = 0.0, 0.0, False, 16


def _render(scene, samples, seed, integrator="PATH"):
    out = ru.render(scene, ru.LANTERN, samples, seed=seed, integrator=integrator)
    st = engine.LAST_RENDER["stats"]
    return np.asarray(out.combined, np.float64)[..., :3], st, out


def _reference(scene_factory, name, integrator):
    key = (name, integrator)
    if key not in _REFS:
        scene = scene_factory(name)
        _reset_halting(scene)
        r1 = _render(scene, REF_SAMPLES, 1000, integrator)[0]
        r2 = _render(scene, REF_SAMPLES, 1001, integrator)[0]
        _REFS[key] = (0.5 * (r1 + r2), float(((r1 - r2) ** 2).sum() / 4.0))
    return _REFS[key]


def measured_error(img, ref):
    r, v_r = ref
    return float(np.sqrt((((img - r) ** 2).sum() - v_r) / ((r * r).sum() - v_r)))


@pytest.mark.parametrize("name,integrator", HONESTY_SCENES)
def test_error_estimate_predicts_the_measured_error(name, integrator, scene_factory):
    ref = _reference(scene_factory, name, integrator)
    scene = scene_factory(name)
    _reset_halting(scene)
    rows, bad = [], []
    for spp in HONESTY_SAMPLES:
        # The estimate claims the expected squared error: compared over HONESTY_POOL / spp renders
        # (RMS of each), as one render's squared error at 4 spp (2 samples a half) scatters over
        # 0.3-2.3x its expectation (measured over 12 seeds on glossy_glass).
        p2 = m2 = 0.0
        seeds = range(7, 7 + max(1, HONESTY_POOL // spp))
        for seed in seeds:
            img, st, _ = _render(scene, spp, seed, integrator)
            p2 += st.rel_error ** 2 / len(seeds)
            m2 += measured_error(img, ref) ** 2 / len(seeds)
        predicted, measured = np.sqrt(p2), np.sqrt(m2)
        ratio = predicted / measured
        rows.append("%s %s %4d spp x %2d renders: predicted %.4f measured %.4f ratio %.3f"
                    % (name, integrator, spp, len(seeds), predicted, measured, ratio))
        if not 1.0 / FACTOR <= ratio <= FACTOR:
            bad.append(rows[-1])
    print("\n".join(rows))
    assert not bad, "\n".join(rows)


def test_noise_target_halts_within_the_target(scene_factory):
    ref = _reference(scene_factory, "cornell_area", "PATH")
    scene = scene_factory("cornell_area")
    _reset_halting(scene)
    target = 0.04
    scene.lantern.noise_target = target
    img, st, _ = _render(scene, 1 << 16, 11)
    measured = measured_error(img, ref)
    print("noise target %.3f: %d samples, estimate %.4f, measured %.4f"
          % (target, st.samples_done, st.rel_error, measured))
    assert st.halt_reason == core.HALT_NOISE_TARGET
    assert 0 < st.rel_error <= target
    assert st.samples_done < 1 << 16
    # The estimate is honest within FACTOR (test above); it stopped at the first pass below the
    # target, so the measured error lies within FACTOR of the target.
    assert target / FACTOR <= measured <= target * FACTOR


def test_time_limit_halts_within_ten_percent(scene_factory):
    scene = scene_factory("cornell_area")
    _reset_halting(scene, 100)
    limit = 2.0
    scene.lantern.time_limit = limit
    t0 = time.perf_counter()
    _, st, _ = _render(scene, 1 << 20, 3)
    wall = time.perf_counter() - t0
    # What the render costs besides sampling (export, BVH, writing the EXR): a 1-sample render.
    scene.lantern.time_limit = 0.0
    t0 = time.perf_counter()
    _render(scene, 1, 3)
    overhead = time.perf_counter() - t0
    print("time limit %.1f s: render %.3f s, operator %.3f s (1-sample operator %.3f s), %d samples"
          % (limit, st.elapsed_seconds, wall, overhead, st.samples_done))
    assert st.halt_reason == core.HALT_TIME_LIMIT
    assert abs(st.elapsed_seconds - limit) <= 0.1 * limit
    assert wall <= 1.1 * limit + overhead


def test_adaptive_sampling_keeps_tile_means_unbiased(scene_factory, outdir):
    """Same rule as test_agreement.py: two seeds per method, tile means within the Bonferroni-
    corrected z bound of both renders' noise (pixels independent for the path tracer)."""
    scene = scene_factory("cornell_area")
    _reset_halting(scene, 100)
    fixed = [_render(scene, 256, seed)[0] for seed in (20, 21)]
    lt = scene.lantern
    lt.noise_target, lt.adaptive, lt.min_samples = 0.02, True, 16
    adaptive, counts, stats = [], [], []
    for seed in (22, 23):
        img, st, out = _render(scene, 1 << 16, seed)
        adaptive.append(img)
        counts.append(out["Sample Count"][..., 0])
        stats.append(st)
    for st, c in zip(stats, counts):
        assert st.halt_reason == core.HALT_NOISE_TARGET
        assert st.rel_error <= 0.02
        # The Sample Count pass shows each pixel's own samples: adaptive sampling varied them.
        assert c.min() >= 16 and c.max() == st.samples_done and c.min() < c.max()
    print("adaptive: samples per pixel %s (mean %.1f) vs fixed 256"
          % ([(int(c.min()), int(c.max())) for c in counts], np.mean(counts)))
    mean_f, se2_f = ru.tile_mean_and_se2(*fixed, 16)
    mean_a, se2_a = ru.tile_mean_and_se2(*adaptive, 16)
    z = ru.bonferroni_z(mean_f.size)
    bound = z * np.sqrt(se2_f + se2_a) + 1e-5 * np.abs(mean_f)
    worst = float((np.abs(mean_a - mean_f) / bound).max())
    print("adaptive vs fixed: worst tile |difference| / bound = %.3f" % worst)
    if worst > 1:
        ru.write_png(os.path.join(outdir, "adaptive.png"), 0.5 * (adaptive[0] + adaptive[1]))
        ru.write_png(os.path.join(outdir, "fixed.png"), 0.5 * (fixed[0] + fixed[1]))
    assert worst <= 1


def test_adaptive_bidirectional_keeps_tile_means_unbiased(scene_factory, outdir):
    """BDPT splats land in any pixel, stopped ones included, divided by the light paths actually
    traced. Splats correlate pixels, so (as in test_agreement.py) each method's tile means and
    their standard errors come from K independent renders, and the bound is Student's t with
    K - 1 degrees of freedom, Bonferroni-corrected over tiles and channels."""
    from test_agreement import student_t_upper
    scene = scene_factory("cornell_point")
    _reset_halting(scene)
    k_runs = 6

    def tile_means(images):
        m = np.array([ru.tile_view(img, 16).mean(axis=2) for img in images])
        return m.mean(axis=0), m.var(axis=0, ddof=1) / len(images)
    fixed = [_render(scene, 64, 40 + k, "BIDIRECTIONAL")[0] for k in range(k_runs)]
    lt = scene.lantern
    lt.noise_target, lt.adaptive, lt.min_samples = 0.06, True, 8
    adaptive = []
    for k in range(k_runs):
        img, st, out = _render(scene, 1 << 12, 60 + k, "BIDIRECTIONAL")
        assert st.halt_reason == core.HALT_NOISE_TARGET and st.rel_error <= 0.06
        c = out["Sample Count"][..., 0]
        assert c.min() < c.max()
        adaptive.append(img)
    mean_f, se2_f = tile_means(fixed)
    mean_a, se2_a = tile_means(adaptive)
    t = student_t_upper(1e-3 / (2.0 * mean_f.size), k_runs - 1)
    bound = t * np.sqrt(se2_f + se2_a) + 1e-5 * np.abs(mean_f)
    worst = float((np.abs(mean_a - mean_f) / bound).max())
    print("adaptive BDPT vs fixed: worst tile |difference| / bound = %.3f" % worst)
    assert worst <= 1


def test_metadata_is_kept_with_the_image(scene_factory, tmp_path):
    scene = scene_factory("cornell_area")
    _reset_halting(scene, 25)
    scene.lantern.noise_target = 0.2
    scene.lantern.min_samples = 4
    out = ru.render(scene, ru.LANTERN, 64, seed=0, outdir=str(tmp_path), keep=True)
    meta = engine.LAST_RENDER["metadata"]
    st = engine.LAST_RENDER["stats"]
    assert meta["lantern.halt_reason"] == "noise target"
    assert float(meta["lantern.rel_error"]) == pytest.approx(st.rel_error, rel=1e-5)
    assert meta["lantern.samples"] == str(st.samples_done)
    with open(out.path, "rb") as f:
        header, _ = ru._read_header(f.read())
    for key in ("lantern.samples", "lantern.rel_error", "lantern.render_seconds",
                "lantern.noise_target", "lantern.halt_reason", "lantern.integrator"):
        assert header[key][1].decode() == meta[key], key
    assert not list(tmp_path.glob("*.json"))  # EXR keeps it: no sidecar
    # TIFF keeps no stamp data: a JSON file beside the image.
    s = scene.render.image_settings
    s.file_format, s.color_depth, s.color_mode = "TIFF", "8", "RGB"
    scene.render.filepath = str(tmp_path / "still")
    import bpy
    bpy.ops.render.render(write_still=True, scene=scene.name)
    assert (tmp_path / "still.tif").is_file()
    with open(tmp_path / "still.lantern.json") as f:
        assert json.load(f) == engine.LAST_RENDER["metadata"]


def test_render_report_says_what_the_scene_used(scene_factory):
    scene = scene_factory("unsupported_node")
    _reset_halting(scene, 25)
    ru.render(scene, ru.LANTERN, 4, seed=0)
    text = engine.LAST_RENDER["report"]
    assert "integrator: path tracing" in text
    assert "lights:" in text and "media: none" in text
    assert "ShaderNodeEeveeSpecular" in text and "Point Density" in text
    assert "Stopped by samples" in text
