"""Animation renders (issue 15): the seed per frame."""
import numpy as np

import render_utils as ru
from lantern import engine


def _frame(scene, frame, animated):
    scene.lantern.use_animated_seed = animated
    scene.frame_set(frame)
    out = ru.render(scene, ru.LANTERN, 8, seed=3).combined[..., :3]
    return out, engine.LAST_RENDER["settings"].seed


def test_animated_seed_gives_each_frame_its_own_noise(scene_factory):
    """Off: a still scene renders the same noise at every frame. On (Cycles' Animated Seed): each
    frame has its own seed, so the noise differs, and the image is the same in the mean."""
    scene = scene_factory("cornell_area")
    scene.render.resolution_x = scene.render.resolution_y = 32
    a, seed_a = _frame(scene, 1, False)
    b, seed_b = _frame(scene, 2, False)
    assert seed_a == seed_b == 3
    assert np.abs(a - b).max() < 1e-3  # same numbers (summation order may differ by rounding)
    c, seed_c = _frame(scene, 1, True)
    d, seed_d = _frame(scene, 2, True)
    assert len({seed_c, seed_d, 3}) == 3
    assert np.abs(c - d).max() > 0.05  # independent noise
    # The same image in the mean: within 5 standard errors of the difference of two renders.
    diff = (c - d).mean(axis=-1)
    se = diff.std() / np.sqrt(diff.size)
    assert abs(diff.mean()) < 5 * se, (diff.mean(), se)
