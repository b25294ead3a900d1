"""The add-on's checks of one Blender datablock's values, and the core's messages about it
reported with the datablock's name instead of the core's index ("light 3", "mesh 0")."""

import re

import numpy as np

from .. import core

FLT_MAX = float(np.finfo(np.float32).max)

_CORE_SUBJECT = re.compile(r"^(?:mesh|curves|points|light|instance|material node) \d+(?::\s*|\s+)")


def without_core_index(message):
    return _CORE_SUBJECT.sub("", message, count=1)


def is_finite(*values):
    try:
        return bool(np.isfinite(np.asarray(values, dtype=np.float64)).all())
    except (TypeError, ValueError):  # ragged: check one by one
        return all(is_finite(*np.ravel(v)) for v in values)


def transform_problem(matrix):
    """Why the core would leave out an object at `matrix` (4x4 or 3x4), or None: a transform that
    is not finite, or one whose volume factor (determinant) overflows single precision, which the
    core cannot invert (e.g. a scale of 1e20 on each axis)."""
    m = np.asarray(matrix, dtype=np.float64)
    if not np.isfinite(m).all() or not np.isfinite(np.asarray(matrix, dtype=np.float32)).all():
        return "its transform is not finite (in single precision)"
    det = float(np.linalg.det(m[:3, :3]))
    if not abs(det) <= FLT_MAX:
        scale = abs(det) ** (1.0 / 3.0)
        return ("its transform scales it by about %.3g, so its volume factor (%.3g) exceeds single "
                "precision (%.3g)" % (scale, abs(det), FLT_MAX))
    return None


def core_call(core_scene, report, subject, method, *args, **kwargs):
    """core_scene.method(*args, **kwargs) for the datablock named by `subject` ("Light 'Lamp'").
    A value the core refuses (the last line of defence behind the add-on's own checks) leaves the
    item out with a warning naming it, and gives None: the render goes on. Warnings the call made
    are reported naming it too."""
    try:
        result = getattr(core_scene, method)(*args, **kwargs)
    except core.LanternError as e:
        if e.status != core.ERROR_INVALID_ARGUMENT:
            raise
        result = None
        report({'WARNING'}, "%s left out: %s" % (subject, without_core_index(e.detail)))
    for w in core_scene.take_warnings():
        report({'WARNING'}, "%s: %s" % (subject, without_core_index(w)))
    return result
