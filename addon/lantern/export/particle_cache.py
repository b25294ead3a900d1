"""Particle hair keys in bulk: the evaluated particle system's path cache, the very memory
ParticleSystem.co_hair reads one key at a time (rna_particle.c: pathcache for parents, childcache
for children, each key's co brought through the system's imat and the object's matrix).

Blender 3.4's Python API has no bulk access to rendered child paths, and co_hair costs about a
microsecond a key from Python. This module finds the cache through Blender's own description of
its structs (SDNA, embedded in the executable), checks that description against values RNA
reports (seed, child seed, particle and child counts) before following any pointer, and checks
sampled strands against co_hair before the caller uses the result. ParticleCacheKey is not a DNA
struct (BKE_particle.h): its layout (co, vel, rot, col, time, segments: 15 four-byte fields, co
first) is checked by the path stride and the sampled strands. Any disagreement returns a reason,
and the caller exports through co_hair.
"""

import ctypes
import re
import struct

import bpy
import numpy as np

KEY_FIELDS = 15  # ParticleCacheKey: float co[3], vel[3], rot[4], col[3], time; int segments
KEY_BYTES = 4 * KEY_FIELDS
SEGMENTS_FIELD = 14
POINTER = ctypes.sizeof(ctypes.c_void_p)
FIELDS = ("**pathcache", "**childcache", "imat[4][4]", "seed", "child_seed", "totpart", "totchild",
          "totcached", "totchildcache")

_layout = None  # {field name: offset} of ParticleSystem, or a str saying why there is none


def _sdna_structs(buf, start):
    """The structs of the SDNA blob at start: {type: [(type, name)]} and {type: size}."""
    p = start + 8  # "SDNA" "NAME"

    def strings(p):
        n, = struct.unpack_from("<i", buf, p)
        p += 4
        out = []
        for _ in range(n):
            end = buf.find(b"\0", p)
            out.append(buf[p:end].decode("latin-1"))
            p = end + 1
        return out, (p + 3) & ~3

    names, p = strings(p)
    if buf[p:p + 4] != b"TYPE":
        raise ValueError("no TYPE block")
    types, p = strings(p + 4)
    if buf[p:p + 4] != b"TLEN":
        raise ValueError("no TLEN block")
    sizes = struct.unpack_from("<%dh" % len(types), buf, p + 4)
    p = (p + 4 + 2 * len(types) + 3) & ~3
    if buf[p:p + 4] != b"STRC":
        raise ValueError("no STRC block")
    count, = struct.unpack_from("<i", buf, p + 4)
    p += 8
    structs = {}
    for _ in range(count):
        t, n = struct.unpack_from("<hh", buf, p)
        pairs = struct.unpack_from("<%dh" % (2 * n), buf, p + 4)
        structs[types[t]] = [(types[pairs[2 * i]], names[pairs[2 * i + 1]]) for i in range(n)]
        p += 4 + 4 * n
    return structs, dict(zip(types, sizes))


def _sdna_blob(path, chunk=1 << 22, most=1 << 21):
    """The bytes from the first SDNA blob in the executable on (at most `most` of them), read in
    chunks rather than mapped, so that the scan adds nothing to the process's resident memory."""
    tail = b""
    with open(path, "rb") as f:
        while True:
            block = f.read(chunk)
            if not block:
                return None
            buf = tail + block
            at = buf.find(b"SDNANAME")
            if at >= 0:
                return buf[at:] + f.read(max(0, most - (len(buf) - at)))
            tail = buf[-7:]


def _offsets(fields, sizes):
    """Field offsets of a DNA struct: makesdna lays fields out without implicit padding."""
    offsets, at = {}, 0
    for type_name, name in fields:
        offsets[name] = at
        count = 1
        for dim in re.findall(r"\[(\d+)\]", name):
            count *= int(dim)
        at += count * (POINTER if name.startswith("*") or name.startswith("(*") else sizes[type_name])
    return offsets


def _particle_system_layout():
    global _layout
    if _layout is None:
        _layout = "no SDNA with ParticleSystem in %s" % bpy.app.binary_path
        try:
            buf = _sdna_blob(bpy.app.binary_path)
            if buf is not None:
                structs, sizes = _sdna_structs(buf, 0)
                if "ParticleSystem" in structs:
                    offsets = _offsets(structs["ParticleSystem"], sizes)
                    missing = [f for f in FIELDS if f not in offsets]
                    _layout = ("ParticleSystem lacks %s" % ", ".join(missing) if missing
                               else {f.lstrip("*").split("[")[0]: offsets[f] for f in FIELDS})
        except (OSError, ValueError, struct.error, KeyError, IndexError) as e:
            _layout = "Blender's SDNA unreadable (%s)" % e
    return _layout


def _view(address, nbytes, dtype):
    return np.frombuffer((ctypes.c_char * nbytes).from_address(address), dtype=dtype)


def object_keys(obj, psys, first, count, steps):
    """Keys of strands first..first+count-1 (particle_no as co_hair numbers them) in object space,
    float64 (count, steps, 3), as Cycles takes them from co_hair and brings them back into object
    space (a step beyond a path's segments repeats the key before), or a str saying why the cache
    cannot be read."""
    layout = _particle_system_layout()
    if isinstance(layout, str):
        return layout
    base = psys.as_pointer()
    ints = {f: int(_view(base + layout[f], 4, np.int32)[0])
            for f in ("seed", "child_seed", "totpart", "totchild", "totcached", "totchildcache")}
    expect = {"seed": psys.seed, "child_seed": psys.child_seed, "totpart": len(psys.particles),
              "totchild": len(psys.child_particles)}
    wrong = [f for f, v in expect.items() if ints[f] != v]
    if wrong:
        return "ParticleSystem layout disagrees with RNA (%s)" % ", ".join(wrong)
    children = first > 0
    if count < 2:
        return "fewer than 2 strands"
    if children and (first != ints["totcached"] or count != ints["totchildcache"]):
        return "child cache holds %d paths after %d parents, not %d after %d" % (
            ints["totchildcache"], ints["totcached"], count, first)
    if not children and count != ints["totcached"]:
        return "path cache holds %d paths, not %d" % (ints["totcached"], count)
    table = int(_view(base + layout["childcache" if children else "pathcache"], POINTER, np.uintp)[0])
    if table == 0:
        return "no path cache"
    paths = _view(table, POINTER * count, np.uintp).astype(np.int64)
    if not paths.all():
        return "a path is missing from the cache"
    # Paths come in buffers of consecutive paths (psys_alloc_path_cache_buffers), each path
    # `stride` bytes after the one before; read each buffer's run at once.
    stride = int(paths[1] - paths[0])
    if stride <= 0 or stride % KEY_BYTES:
        return "path stride %d is not a whole number of %d-byte keys" % (stride, KEY_BYTES)
    keys = stride // KEY_BYTES
    read = min(keys, steps)
    # co_hair: the system's imat (Blender's column-major m[column][row]) into world space, then the
    # object's matrix; Cycles applies the object's inverse: imat alone brings the key home.
    imat = _view(base + layout["imat"], 64, np.float32).reshape(4, 4).astype(np.float64)
    co = np.empty((count, steps, 3), dtype=np.float64)
    segments = np.empty(count, dtype=np.int64)
    starts = np.flatnonzero(np.diff(paths) != stride) + 1
    for a, b in zip(np.concatenate([[0], starts]), np.concatenate([starts, [count]])):
        # One buffer's run at a time: its temporaries stay small.
        run = _view(int(paths[a]), int(b - a) * stride, np.float32).reshape(b - a, keys, KEY_FIELDS)
        out = co[a:b, :read]
        out[...] = imat[3, :3]
        for i in range(3):  # elementwise: a 3x3 product through BLAS costs more than it does
            out += run[:, :read, i:i + 1] * imat[i, :3]
        segments[a:b] = run[:, 0, SEGMENTS_FIELD].view(np.int32)
    if children:  # co_hair: a child cut off (segments < 0) still gives its first key
        np.maximum(segments, 0, out=segments)
    np.minimum(segments, read - 1, out=segments)  # a path holds `keys` keys: co_hair reads no further
    # co_hair leaves a step beyond the path's segments unwritten: Cycles then repeats the key before.
    for j in range(1, steps):
        unwritten = segments < j
        if unwritten.any():
            co[unwritten, j] = co[unwritten, j - 1]
    if (segments < 0).any():  # a path with no keys: every call unwritten, Cycles' keys at the world's origin
        co[segments < 0] = np.linalg.inv(np.array(obj.matrix_world, dtype=np.float64))[:3, 3]
    return co
