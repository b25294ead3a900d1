"""Hair export, BVH build and memory against Cycles' (issue 15): the hair ball with N strands (N/4
parents x 4 interpolated children, 9 keys), rendered at 64x64 with 1 sample, each engine in its own
`blender -b` process, all in one run of this script:

    python3 bench/hair_export.py --library build/liblantern.so [--strands 100000,1000000]

Engines: Lantern (hair keys read from the path cache in bulk, export/particle_cache.py), Lantern
with the cache read withheld (co_hair key by key: the export before it), Cycles, and a baseline
process that builds the scene without rendering. Phases are timed from Blender's own status lines
(each stamped by this script as it arrives): "export" from the render's first status line to the
BVH build (Lantern: "Building acceleration structures"; Cycles: "Updating Scene BVH"), "BVH" from
there to the next phase; "total" is the render operator's wall time. Memory: the process's peak
resident set (os.wait4's ru_maxrss) less the baseline's, per strand segment (8 per strand); it
counts all a render adds, Blender's render-time particle cache included (the same for both
engines). Lantern's phases are also timed from inside (keys: particle_hair_arrays; add_curves;
commit: the BVH build), with the process's CPU time, which load on a shared machine does not
inflate as it does wall time. Nothing asserts on time or memory.
"""
import argparse
import os
import re
import subprocess
import sys
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
ENGINES = ("baseline", "lantern", "lantern_co_hair", "cycles")
KEYS = (1 << 3) + 1


def _memory():
    """(resident, peak resident) bytes of this process (/proc/self/status)."""
    with open("/proc/self/status") as f:
        kb = {l.split(":")[0]: int(l.split()[1]) for l in f if l.startswith(("VmRSS", "VmHWM"))}
    return kb["VmRSS"] * 1024, kb["VmHWM"] * 1024


def _probe(owner, name, label):
    """Wraps owner.name to print its wall time and the process's memory after it."""
    inner = getattr(owner, name)

    def timed(*a, **k):
        t0, c0 = time.perf_counter(), time.process_time()
        out = inner(*a, **k)
        rss, hwm = _memory()
        print("BENCH %s %.3f s rss %d hwm %d cpu %.3f" % (label, time.perf_counter() - t0, rss, hwm,
                                                          time.process_time() - c0), flush=True)
        return out
    setattr(owner, name, timed)


def worker(engine, strands):
    sys.path[:0] = [os.path.join(REPO, "scenes"), os.path.join(REPO, "addon")]
    import lantern
    lantern.register()
    import build_scenes
    import render_utils as ru
    from lantern.export import hair, particle_cache
    build_scenes.reset_file()
    scene = build_scenes.new_scene("hair_bench", (64, 64), 1)
    build_scenes.build_hair_ball(scene, strands=strands // 4, children=4, principled=True)
    if engine == "baseline":
        scene.view_layers[0].depsgraph.update()
        return
    if engine == "lantern_co_hair":
        particle_cache._layout = "withheld by bench/hair_export.py"
    if engine.startswith("lantern"):
        _probe(hair, "particle_hair_arrays", "keys")
        _probe(lantern.core.Scene, "add_curves", "add_curves")
        _probe(lantern.core.Scene, "commit", "commit")
    t0 = time.perf_counter()
    ru.render(scene, ru.CYCLES if engine == "cycles" else ru.LANTERN, 1, seed=0)
    print("BENCH total %.3f" % (time.perf_counter() - t0), flush=True)


def measure(args, engine, strands):
    env = dict(os.environ, LANTERN_LIBRARY=os.path.abspath(args.library))
    cmd = [args.blender, "-b", "--factory-startup", "--python", os.path.abspath(__file__), "--",
           "--worker", engine, "--strands", str(strands)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                            cwd=REPO)
    lines = [(time.perf_counter(), line.rstrip()) for line in proc.stdout]
    _, status, usage = os.wait4(proc.pid, 0)
    if status != 0 or (engine != "baseline" and not any(l.startswith("BENCH total") for _, l in lines)):
        sys.exit("%s failed:\n%s" % (engine, "\n".join(l for _, l in lines[-30:])))
    row = {"peak": usage.ru_maxrss * 1024}
    if engine == "baseline":
        return row
    row["total"] = float(next(l.split()[2] for _, l in lines if l.startswith("BENCH total")))
    status_lines = [(t, l) for t, l in lines if l.startswith("Fra:")]
    bvh = "Building acceleration structures" if engine.startswith("lantern") else "Updating Scene BVH"
    start = status_lines[0][0]
    i = next(i for i, (_, l) in enumerate(status_lines) if bvh in l)
    j = next(j for j in range(i, len(status_lines)) if not re.search(r"BVH|acceleration", status_lines[j][1]))
    row["export"] = status_lines[i][0] - start
    row["bvh"] = status_lines[j][0] - status_lines[i][0]
    for _, l in lines:
        if l.startswith("BENCH ") and not l.startswith("BENCH total"):
            w = l.split()
            row[w[1]] = float(w[2])
            row[w[1] + "_rss"], row[w[1] + "_hwm"], row[w[1] + "_cpu"] = int(w[5]), int(w[7]), float(w[9])
    warnings = [l for _, l in lines if "co_hair" in l and "Warning" in l]
    row["note"] = "co_hair warning" if warnings else ""
    return row


def main():
    if "--worker" in sys.argv:
        a = sys.argv[sys.argv.index("--") + 1:]
        worker(a[a.index("--worker") + 1], int(a[a.index("--strands") + 1]))
        return
    p = argparse.ArgumentParser()
    p.add_argument("--library", default=os.path.join(REPO, "build", "liblantern.so"))
    p.add_argument("--blender", default="blender")
    p.add_argument("--strands", default="100000")
    p.add_argument("--engines", default=",".join(ENGINES))
    args = p.parse_args()
    for strands in map(int, args.strands.split(",")):
        rows = {e: measure(args, e, strands) for e in args.engines.split(",")}
        base = rows.get("baseline", {}).get("peak", 0)
        segments = strands * (KEYS - 1)
        for e, r in rows.items():
            if e == "baseline":
                print("strands %d baseline peak %.1f MiB" % (strands, r["peak"] / 2**20))
                continue
            print("strands %d %-16s total %7.2f s  export %7.2f s  BVH %6.2f s  peak %7.1f MiB  "
                  "+%6.1f B/segment %s" % (strands, e, r["total"], r["export"], r["bvh"], r["peak"] / 2**20,
                                           (r["peak"] - base) / segments, r["note"]), flush=True)
            if "keys" in r:
                print("    of it: keys %.2f s (CPU %.2f s), add_curves %.2f s, commit %.2f s (CPU %.2f s); resident "
                      "after keys %+.1f, after add_curves %+.1f, after commit %+.1f B/segment over the baseline's peak"
                      % (r["keys"], r["keys_cpu"], r["add_curves"], r["commit"], r["commit_cpu"],
                         (r["keys_rss"] - base) / segments,
                         (r["add_curves_rss"] - base) / segments, (r["commit_rss"] - base) / segments))


if __name__ == "__main__":
    main()
