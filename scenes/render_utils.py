"""Rendering and image helpers for the Blender tests (run inside Blender's Python).

Images are numpy float32 arrays shaped (height, width, channels), rows from the TOP of the image
(as OpenEXR stores them; Blender's Image.pixels and the core's pass buffers go bottom to top).

A render is written to a 32-bit float multilayer OpenEXR and read back with the small reader below
(NONE, ZIPS, ZIP codecs; HALF/FLOAT/UINT channels), so every pass of one render comes back at once.
Blender writes scene-linear values to EXR whatever the view transform; test_harness.py checks the
reader against bpy.data.images.load and the linearity against an emission plane of strength 1.
"""
import math
import os
import struct
import tempfile
import time
import zlib

import numpy as np

import bpy

CYCLES = "CYCLES"
LANTERN = "LANTERN"

# ----------------------------------------------------------------------------------------------
# OpenEXR (scanline, single part) reader
# ----------------------------------------------------------------------------------------------
_EXR_MAGIC = 20000630
_LINES_PER_BLOCK = {0: 1, 2: 1, 3: 16}  # NONE, ZIPS, ZIP
_DTYPES = {0: np.dtype("<u4"), 1: np.dtype("<f2"), 2: np.dtype("<f4")}


def _read_header(data):
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != _EXR_MAGIC:
        raise ValueError("not an OpenEXR file")
    if version & 0x1A00:  # tiled, deep or multi-part
        raise ValueError("only single-part scanline OpenEXR is supported (version flags %#x)" % version)
    pos = 8
    header = {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        pos = end + 1
        end = data.index(b"\0", pos)
        typ = data[pos:end].decode()
        pos = end + 1
        (size,) = struct.unpack_from("<i", data, pos)
        pos += 4
        header[name] = (typ, data[pos:pos + size])
        pos += size
    return header, pos + 1


def _parse_channels(raw):
    channels, pos = [], 0
    while raw[pos] != 0:
        end = raw.index(b"\0", pos)
        name = raw[pos:end].decode()
        pixel_type, _plinear, xs, ys = struct.unpack_from("<iB3xii", raw, end + 1)
        if xs != 1 or ys != 1:
            raise ValueError("subsampled channels are not supported")
        channels.append((name, pixel_type))
        pos = end + 1 + 16
    return channels


def _unzip(block, expected):
    if len(block) == expected:  # the writer stores a block raw when compression does not help
        return np.frombuffer(block, np.uint8)
    t = np.frombuffer(zlib.decompress(block), np.uint8).astype(np.int64)
    if t.size != expected:
        raise ValueError("bad ZIP block size")
    t[1:] -= 128
    t = (np.cumsum(t) & 0xFF).astype(np.uint8)  # undo the predictor
    out = np.empty_like(t)
    half = (t.size + 1) // 2
    out[0::2] = t[:half]  # undo the byte interleave
    out[1::2] = t[half:]
    return out


def read_exr(path):
    """All channels of an OpenEXR file: {channel name: float32 array (h, w)}, rows top first."""
    with open(path, "rb") as f:
        data = f.read()
    header, pos = _read_header(data)
    channels = sorted(_parse_channels(header["channels"][1]), key=lambda c: c[0])
    compression = header["compression"][1][0]
    if compression not in _LINES_PER_BLOCK:
        raise ValueError("unsupported EXR compression %d (use NONE, ZIPS or ZIP)" % compression)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", header["dataWindow"][1])
    width, height = xmax - xmin + 1, ymax - ymin + 1
    lines = _LINES_PER_BLOCK[compression]
    nblocks = (height + lines - 1) // lines
    offsets = struct.unpack_from("<%dQ" % nblocks, data, pos)
    out = {name: np.zeros((height, width), np.float32) for name, _ in channels}
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        block = data[off + 8:off + 8 + size]
        y0 = y - ymin
        n = min(lines, height - y0)
        expected = n * width * sum(_DTYPES[t].itemsize for _, t in channels)
        buf = np.frombuffer(block, np.uint8) if compression == 0 else _unzip(block, expected)
        p = 0
        for row in range(n):
            for name, t in channels:
                nbytes = width * _DTYPES[t].itemsize
                out[name][y0 + row] = np.frombuffer(buf[p:p + nbytes].tobytes(), _DTYPES[t])
                p += nbytes
    return out


_CHANNEL_ORDERS = ("RGBA", "XYZW", "UVA")


def _order_key(chans):
    for order in _CHANNEL_ORDERS:
        if set(chans) <= set(order):
            return order.index
    return None


def read_multilayer_exr(path):
    """Passes of a Blender multilayer EXR: {pass name: float32 array (h, w, c)}.

    Channels are named "ViewLayer.Pass.C"; the view layer part is dropped (one layer per render),
    a plain EXR's "R", "G", "B", "A" channels come back as the pass "Combined". Channels are
    ordered RGBA / XYZW / UVA when their letters fit, else alphabetically."""
    chans = read_exr(path)
    groups = {}
    for name, arr in chans.items():
        parts = name.split(".")
        pass_name = parts[-2] if len(parts) >= 2 else "Combined"
        groups.setdefault(pass_name, {})[parts[-1]] = arr
    passes = {}
    for pass_name, cs in groups.items():
        names = list(cs)
        key = _order_key(names)
        names.sort(key=key) if key else names.sort()
        passes[pass_name] = np.stack([cs[c] for c in names], axis=-1)
    return passes


def load_image_pixels(path):
    """An image file through Blender's own loader: float32 (h, w, 4), rows top first."""
    img = bpy.data.images.load(path, check_existing=False)
    try:
        w, h = img.size
        px = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(px)
        return px.reshape(h, w, 4)[::-1].copy()
    finally:
        bpy.data.images.remove(img)


# ----------------------------------------------------------------------------------------------
# PNG preview writer (no dependencies): for looking at renders
# ----------------------------------------------------------------------------------------------
def to_srgb8(img, exposure=0.0):
    x = np.clip(np.asarray(img, np.float64)[..., :3] * (2.0 ** exposure), 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255 + 0.5).astype(np.uint8)


def write_png(path, img, exposure=0.0):
    """Writes a linear (h, w, >=3) image (rows top first) as an 8-bit sRGB PNG."""
    write_png_values(path, to_srgb8(img, exposure))


def write_png_values(path, values, level=6):
    """Writes uint8 or uint16 values (h, w, channels 1 to 4: grey, grey and alpha, RGB, RGBA;
    rows top first) as a PNG of that depth."""
    values = np.asarray(values)
    bits = 16 if values.dtype == np.uint16 else 8
    if values.ndim == 2:
        values = values[..., None]
    h, w, c = values.shape
    rows = values.astype(">u2" if bits == 16 else np.uint8)
    raw = b"".join(b"\0" + rows[y].tobytes() for y in range(h))

    def chunk(tag, payload):
        c = struct.pack(">I", len(payload)) + tag + payload
        return c + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)

    color_type = {1: 0, 2: 4, 3: 2, 4: 6}[c]
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, bits, color_type, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, level)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


# ----------------------------------------------------------------------------------------------
# Rendering
# ----------------------------------------------------------------------------------------------
def engine_registered(idname=LANTERN):
    return any(getattr(c, "bl_idname", None) == idname for c in bpy.types.RenderEngine.__subclasses__())


def export(scene):
    """Exports and commits the scene as a Lantern render would, into a scene that is then freed.
    Returns (the export summary, with the committed scene's lt_scene_stats as "stats", the messages
    it reported)."""
    from lantern import core
    from lantern.export import export_scene
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    reports = []
    core_scene = core.Scene()
    try:
        summary = export_scene(depsgraph, core_scene, lambda level, message: reports.append(message))
        core_scene.commit()
        summary["stats"] = core_scene.stats()
    finally:
        core_scene.close()
    return summary, reports


# Cycles settings that the Lantern settings mirror (same names where the add-on has them).
_BOUNCES = {
    "max_bounces": "max_bounces",
    "diffuse_bounces": "diffuse_bounces",
    "glossy_bounces": "glossy_bounces",
    "transmission_bounces": "transmission_bounces",
    "transparent_bounces": "transparent_max_bounces",
    "volume_bounces": "volume_bounces",
    "clamp_direct": "sample_clamp_direct",
    "clamp_indirect": "sample_clamp_indirect",
}


def configure(scene, engine, samples, seed, threads=2, integrator="PATH"):
    """Sets the engine, its samples and seed, and the thread count. For Lantern the light-path
    settings are copied from the scene's Cycles settings so both engines render the same thing."""
    scene.render.engine = engine
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    if engine == CYCLES:
        scene.cycles.samples = samples
        scene.cycles.seed = seed
    elif engine == LANTERN:
        lt = scene.lantern
        lt.samples = samples
        lt.seed = seed
        lt.integrator = integrator
        for name, cycles_name in _BOUNCES.items():
            if hasattr(lt, name):
                setattr(lt, name, getattr(scene.cycles, cycles_name))
    else:
        raise ValueError("unknown engine %r" % engine)


def _exr_settings(scene, multilayer=True):
    s = scene.render.image_settings
    s.file_format = "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR"
    s.color_mode = "RGBA"
    s.color_depth = "32"
    s.exr_codec = "ZIP"
    scene.render.use_file_extension = True
    scene.render.use_compositing = False
    scene.render.use_sequencer = False


def render_frames_with_persistent_data(scene, filepath, frames=(1, 2)):
    """Renders `frames` with Lantern (4 samples) and Persistent Data into multilayer EXRs named
    filepath + the frame number, as `blender -a` does; returns the add-on's scene_sync counters
    (an edit a committed scene cannot take shows as a full export)."""
    import bpy
    from lantern import engine
    scene.frame_start, scene.frame_end = frames[0], frames[-1]
    configure(scene, LANTERN, 4, 0)
    _exr_settings(scene)
    scene.render.use_persistent_data = True
    scene.render.filepath = filepath
    try:
        bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        scene.render.use_persistent_data = False
    return engine.LAST_RENDER["scene_sync"]


class RenderOutput(dict):
    """Passes of one render ({name: (h, w, c) float32}) plus .seconds, .path, .status."""

    seconds = 0.0
    path = ""
    status = None

    @property
    def combined(self):
        return self["Combined"]


def render(scene, engine=CYCLES, samples=64, seed=0, threads=2, outdir=None, tag=None,
           keep=False, integrator="PATH"):
    """Renders `scene` with `engine` and returns its passes (RenderOutput).

    The render goes to a float multilayer EXR; the Render Result is also saved when the
    operator does not write it (a cancelled render), so a partial image can still be read."""
    configure(scene, engine, samples, seed, threads, integrator)
    _exr_settings(scene)
    outdir = outdir or tempfile.mkdtemp(prefix="lantern_test_")
    tag = tag or "%s_%s_s%d_seed%d" % (scene.name, engine.lower(), samples, seed)
    base = os.path.join(outdir, tag)
    scene.render.filepath = base
    path = base + ".exr"
    if os.path.exists(path):
        os.remove(path)
    t0 = time.perf_counter()
    status = bpy.ops.render.render(write_still=True, scene=scene.name)
    seconds = time.perf_counter() - t0
    if not os.path.exists(path):
        result = bpy.data.images.get("Render Result")
        if result is None:
            raise RuntimeError("render of %s with %s wrote nothing (%s)" % (scene.name, engine, status))
        result.save_render(path, scene=scene)
    out = RenderOutput(read_multilayer_exr(path))
    out.seconds, out.path, out.status = seconds, path, status
    if not keep:
        os.remove(path)
    return out


# ----------------------------------------------------------------------------------------------
# Statistics
# ----------------------------------------------------------------------------------------------
def normal_quantile_upper(p):
    """z with P(Z > z) = p for a standard normal Z: bisection on erfc (no scipy)."""
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 0.5 * math.erfc(mid / math.sqrt(2.0)) > p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def bonferroni_z(n_tests, family_alpha=1e-3):
    """Two-sided critical z for n_tests simultaneous tests at family-wise false-alarm rate alpha."""
    return normal_quantile_upper(family_alpha / (2.0 * n_tests))


def tile_view(img, tile):
    """(h, w, c) → (th, tw, tile*tile, c), dropping partial edge tiles."""
    h, w, c = img.shape
    th, tw = h // tile, w // tile
    x = img[:th * tile, :tw * tile].reshape(th, tile, tw, tile, c)
    return x.transpose(0, 2, 1, 3, 4).reshape(th, tw, tile * tile, c)


def tile_mean_and_se2(run_a, run_b, tile=16):
    """Tile means of the average of two independent renders, and the squared standard error of
    those means: per pixel the noise variance of one render is (a-b)^2/2, of their average
    (a-b)^2/4; pixels are independent, so the tile mean's variance is that summed over the tile
    divided by N^2."""
    a = np.asarray(run_a, np.float64)[..., :3]
    b = np.asarray(run_b, np.float64)[..., :3]
    mean = tile_view(0.5 * (a + b), tile).mean(axis=2)
    d = tile_view(a - b, tile)
    n = d.shape[2]
    se2 = (d * d / 4.0).sum(axis=2) / (n * n)
    return mean, se2


def image_mean_and_se2(runs, independent_pixels=True):
    """The image mean (over pixels, of the RGB average) of the average of `runs`, and its squared
    standard error. With independent pixels, from two renders' per-pixel noise as in
    tile_mean_and_se2 (many degrees of freedom); otherwise (BDPT's splats tie pixels together)
    from the spread of the runs' own image means (len(runs) - 1 degrees of freedom)."""
    means = [np.asarray(r, np.float64)[..., :3].mean(axis=-1) for r in runs]
    if independent_pixels:
        assert len(runs) == 2, "the per-pixel noise estimate takes two renders"
        d = means[0] - means[1]
        return 0.5 * float((means[0] + means[1]).mean()), float((d * d / 4.0).sum()) / d.size ** 2
    m = np.array([x.mean() for x in means])
    return float(m.mean()), float(m.var(ddof=1)) / len(m)


# A global image-mean check beside every per-tile check: a bias of a few percent spread over the
# image hides in per-tile noise, not in the mean of the whole image.
MEAN_Z = 3.0         # standard errors of the two images' combined noise
MEAN_POWER = 0.005   # that noise must be below this fraction of the mean, else the check is blind


def denoise_mean_shift(denoised, noisy, variance):
    """How far denoising moved the image mean, per RGB channel: (sum denoised - sum noisy) in
    standard errors of the noisy mean, sqrt(sum of the Variance pass) (the variance of each pixel's
    mean; camera samples only, so BDPT's splats are not in it); and that standard error as a
    fraction of the noisy mean (the check's power). The issue's promise and the native test
    Denoise.KeepsTheMeanWithinTheNoise: within 5 standard errors (the project's bound)."""
    d, n = (np.asarray(x, np.float64)[..., :3].reshape(-1, 3) for x in (denoised, noisy))
    se = np.sqrt(np.asarray(variance, np.float64)[..., :3].reshape(-1, 3).sum(axis=0))
    dsum, nsum = d.sum(axis=0), n.sum(axis=0)
    return [float(x) for x in (dsum - nsum) / se], [float(x) for x in se / np.maximum(nsum, 1e-30)]


def global_mean_report(name, a, b, labels=("Lantern", "Cycles"), rounding=1e-5, z=MEAN_Z):
    """a, b: (image mean, squared standard error) of two engines or integrators. Returns "" when the
    means agree within z combined standard errors (plus `rounding` relative) and that noise is
    under MEAN_POWER of the mean, else a line saying which failed. z: MEAN_Z for errors known with
    many degrees of freedom; for one estimated from a few runs' spread, the Student t quantile of
    the same false-alarm rate (test_agreement.py)."""
    (ma, sa), (mb, sb) = a, b
    se = math.sqrt(sa + sb)
    line = "%s: image mean %s %.6f, %s %.6f (ratio %.4f), combined standard error %.6f (%.3f%%)" % (
        name, labels[0], ma, labels[1], mb, ma / mb if mb else float("nan"), se, 100 * se / abs(mb) if mb else 0)
    if not se <= MEAN_POWER * abs(mb):
        return line + ": noise above %.1f%% of the mean, render more samples" % (100 * MEAN_POWER)
    if abs(ma - mb) > z * se + rounding * abs(mb):
        return line + ": differ by more than %.2f standard errors" % z
    return ""


def tile_report(name, mean_l, mean_c, bound, outdir, images, labels=("Lantern", "Cycles")):
    """The 8 tiles furthest past their bound, as text; writes `images` ({tag: image}) as PNGs."""
    diff = np.abs(mean_l - mean_c)
    order = np.argsort((diff / np.maximum(bound, 1e-30)).ravel())[::-1][:8]
    lines = ["%s: tile (row %d, col %d) channel %d: %s %.5f %s %.5f |d| %.5f bound %.5f"
             % (name, i // 3 // mean_l.shape[1], i // 3 % mean_l.shape[1], i % 3, labels[0],
                mean_l.ravel()[i], labels[1], mean_c.ravel()[i], diff.ravel()[i], bound.ravel()[i])
             for i in order]
    for tag, img in images.items():
        write_png(os.path.join(outdir, "%s_%s.png" % (name, tag)), img)
    return "\n".join(lines)


def two_seed_agreement(scene, samples, integrator, name, outdir, tile=16, rounding=1e-5):
    """test_agreement.py's rule for independent pixels: each engine renders seeds 0 and 1; every
    tile mean and RGB channel must agree within a Bonferroni z bound (family-wise false alarms
    1e-3) of both engines' noise, plus `rounding` relative (float32 and EXR), and the image means
    as global_mean_report says. Lantern's renders must be finite. Returns (report, Lantern's tile
    means); the report is "" when all agree."""
    runs = {engine: [render(scene, engine, samples, seed=s, integrator=integrator).combined for s in (0, 1)]
            for engine in (CYCLES, LANTERN)}
    return agreement_report(name, runs[LANTERN], runs[CYCLES], outdir, tile, rounding)


def agreement_report(name, runs_a, runs_b, outdir, tile=16, rounding=1e-5, labels=("lantern", "cycles")):
    """two_seed_agreement's rule on two renders (seeds 0 and 1) of each side: returns (report, the
    first side's tile means)."""
    for img in runs_a:
        assert np.isfinite(img).all(), "%s: non-finite pixels" % name
    mean_b, se2_b = tile_mean_and_se2(*runs_b, tile)
    mean_a, se2_a = tile_mean_and_se2(*runs_a, tile)
    bound = bonferroni_z(mean_b.size) * np.sqrt(se2_b + se2_a) + rounding * np.abs(mean_b)
    report = global_mean_report(name, image_mean_and_se2(runs_a), image_mean_and_se2(runs_b),
                                (labels[0].capitalize(), labels[1].capitalize()), rounding)
    if not (np.abs(mean_a - mean_b) <= bound).all():
        report = "\n".join(filter(None, (report, tile_report(
            name, mean_a, mean_b, bound, outdir, {labels[0]: 0.5 * sum(runs_a), labels[1]: 0.5 * sum(runs_b)},
            (labels[0].capitalize(), labels[1].capitalize())))))
    return report, mean_a
