"""Error-against-time curves shared by the benchmarks."""
import math


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
