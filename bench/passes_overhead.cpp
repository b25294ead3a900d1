// The cost of Cycles' light and data passes (docs/passes.md): the Cornell box at 128x128, 32
// samples, one thread, rendered with Blender's default passes, with every light and data pass, and
// with the AO pass besides (one more ray per camera sample), alternately three times each; prints
// the ratios of the times (bench/README.md).
#include <chrono>
#include <cstdio>

#include "../tests/native/scene_builders.h"
using namespace lt_test;
int main() {
  ScenePtr s = cornell_scene();
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    double t[3] = {0, 0, 0};
    for (int rep = 0; rep < 3; ++rep)
      for (int with = 0; with < 3; ++with) {
        lt_render_settings rs = render_settings(128, 128, 32, 1);
        rs.integrator = integrator;
        rs.threads = 1;
        rs.passes = (1u << LT_PASS_COMBINED) | (1u << LT_PASS_DEPTH);
        if (with)
          for (int p = LT_PASS_DIFFUSE_DIRECT; p <= LT_PASS_MATERIAL_INDEX; ++p) rs.passes |= 1u << p;
        if (with == 2) rs.passes |= 1u << LT_PASS_AO;
        auto t0 = std::chrono::steady_clock::now();
        lt_render* r = nullptr;
        check(lt_render_start(s.get(), &rs, &r), "start");
        check(lt_render_wait(r), "wait");
        lt_render_destroy(r);
        t[with] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
    std::printf("%s: default passes %.2f s, + light and data passes %.2f s, ratio %.3f; + AO %.2f s, ratio %.3f\n",
                integrator == LT_INTEGRATOR_PATH ? "PATH" : "BIDIRECTIONAL", t[0], t[1], t[1] / t[0], t[2],
                t[2] / t[0]);
  }
}
