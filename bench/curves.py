"""Error-against-time curves shared by the benchmarks."""
import math

import numpy as np


def interp_loglog(ts, ys, t):
    """log y interpolated linearly in log t at t (ts ascending); None outside [ts[0], ts[-1]]."""
    pts = [(math.log(a), math.log(b)) for a, b in zip(ts, ys) if a > 0 and b is not None and b > 0]
    if not pts:
        return None
    pts.sort()
    lt = math.log(t)
    if lt < pts[0][0] - 1e-9 or lt > pts[-1][0] + 1e-9:
        return None
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= lt <= x1:
            w = 0.0 if x1 == x0 else (lt - x0) / (x1 - x0)
            return math.exp(y0 + w * (y1 - y0))
    return math.exp(pts[0][1]) if abs(lt - pts[0][0]) < 1e-9 else math.exp(pts[-1][1])


# relMSE (Rousselle et al. 2011) against a reference: mean over pixels and RGB of
# (x - ref)^2 / (ref^2 + EPS).
EPS = 1e-2


def rgb(img):
    return np.asarray(img, np.float64)[..., :3]


def pixel_errors(x, ref):
    """Per pixel, the mean over RGB of (x - ref)^2 / (ref^2 + EPS)."""
    return ((rgb(x) - ref) ** 2 / (ref * ref + EPS)).mean(axis=-1)


def reference_from_chunks(chunks):
    """The mean of K independent renders (RGB) as the reference, and its own noise per pixel in
    relMSE units, mean over RGB of Var(ref) / (ref^2 + EPS) (Var from the chunks' spread): a
    measured relMSE is the method's own plus this term (its mean, the "floor")."""
    chunks = np.stack([rgb(c) for c in chunks])
    k = chunks.shape[0]
    ref = chunks.mean(axis=0)
    var_ref = ((chunks - ref) ** 2).sum(axis=0) / (k * (k - 1))
    floor_map = (var_ref / (ref * ref + EPS)).mean(axis=-1)
    return ref, floor_map, float(floor_map.mean())
