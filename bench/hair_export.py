"""Hair export and BVH build against Cycles' (issue 15): the hair ball with N strands (parents x
children), rendered with 1 sample by each engine in one run; prints each engine's wall time of a
1-sample render (export + BVH build + 1 sample), Lantern's export time and the ratio.

    LANTERN_LIBRARY=build/liblantern.so blender -b --factory-startup --python bench/hair_export.py -- 100000
"""
import sys
import time

sys.path.insert(0, "scenes")
sys.path.insert(0, "addon")
import lantern  # noqa: E402
lantern.register()
import build_scenes  # noqa: E402
import render_utils as ru  # noqa: E402

strands = int(sys.argv[sys.argv.index("--") + 1]) if "--" in sys.argv else 100000
build_scenes.reset_file()
scene = build_scenes.new_scene("hair_bench", (64, 64), 1)
build_scenes.build_hair_ball(scene, strands=strands // 4, children=4, principled=True)
seconds = {}
for engine in (ru.LANTERN, ru.CYCLES):
    t0 = time.perf_counter()
    ru.render(scene, engine, 1, seed=0)
    seconds[engine] = time.perf_counter() - t0
print("strands %d (x %d keys): Lantern %.2f s, Cycles %.2f s, Lantern / Cycles %.2f"
      % (strands, (1 << 3) + 1, seconds[ru.LANTERN], seconds[ru.CYCLES], seconds[ru.LANTERN] / seconds[ru.CYCLES]))
