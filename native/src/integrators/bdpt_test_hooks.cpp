// Test hooks of bidirectional path tracing (bdpt_test_hooks.h): compiled into the library, which
// the tests link, and kept out of the integrator's own file.
#include "integrators/bdpt_test_hooks.h"

#include "integrators/bdpt.h"

namespace lt {

std::vector<float> Bdpt::weight_sums() {
  std::vector<float> sums;
  const size_t capacity = size_t(std::max(s_.max_camera_length, s_.max_light_length)) + size_t(s_.max_bounces) + 4;
  // Reused buffers: a vertex is kilobytes, and fresh vectors per sample cost more in page faults
  // than the check itself.
  thread_local std::vector<PathVertex> camera, light, x, C, L, c3;
  if (camera.size() < capacity) {
    camera.resize(capacity);
    light.resize(capacity);
  }
  int nt = generate_camera_subpath(camera);
  int ns = generate_light_subpath(light);
  for (int t = 2; t <= nt; ++t)
    for (int s = 2; s <= ns; ++s) {
      if (s + t - 2 > max_depth()) break;
      PathVertex &qs = light[s - 1], &pt = camera[t - 1];
      if (!scatters(pt) || !scatters(qs) || is_black(transmittance(qs, pt, kVisLightRay))) continue;
      if (is_black(f_cos(qs, normalize(pt.p - qs.p), Mode::Importance)) ||
          is_black(f_cos(pt, normalize(qs.p - pt.p), Mode::Radiance)))
        continue;
      // The full path x[0] = camera ... x[k] = light, with both densities of every vertex:
      // cam[i] (sampled from x[i-1]) and lig[i] (sampled from x[i+1]).
      const int k = s + t - 1;
      x.resize(k + 1);
      for (int i = 0; i < t; ++i) x[i] = camera[i];
      for (int i = 0; i < s; ++i) x[t + i] = light[s - 1 - i];
      std::vector<float> cam(k + 1), lig(k + 1);
      for (int i = 0; i < t; ++i) {
        cam[i] = camera[i].pdf_fwd;
        lig[i] = camera[i].pdf_rev;
      }
      for (int i = 0; i < s; ++i) {
        lig[t + i] = light[s - 1 - i].pdf_fwd;
        cam[t + i] = light[s - 1 - i].pdf_rev;
      }
      // Densities across the connection, which neither walk produced.
      lig[t - 1] = pdf(qs, s > 1 ? &light[s - 2] : nullptr, pt, pixel_center_);
      lig[t - 2] = pdf(pt, &qs, camera[t - 2], pixel_center_);
      cam[t] = pdf(pt, &camera[t - 2], qs, pixel_center_);
      cam[t + 1] = pdf(qs, &pt, light[s - 2], pixel_center_);
      lig[k] = light[0].pdf_fwd;
      // Cycles' bounce-kind limits scale every strategy's contribution by the same factor (see
      // kind_limit_factor): the weights times each strategy's factor, over the factor this
      // connection gets in the render, must sum to one too. Inside the joined path every vertex
      // has both neighbours; the ones the walks did not store are set here.
      const float factor = kind_limit_factor(light, camera, s, t);
      if (!(factor > 0)) continue;
      for (int i = 1; i < k; ++i)
        if (x[i].type == VertexType::Surface && x[i].kind == BounceKind::Mixed &&
            !mixed_kind(x[i], x[i - 1].p, x[i + 1].p, i != t - 1 && i != t && x[i].delta, x[i].kind_p))
          x[i].kind_p[0] = -1;
      // The path as every strategy sees it: camera-side prefixes of C, light-side prefixes of
      // L (reversed); mis_weight reads only the first t2 and s2 entries (and restores what it
      // assigns), so the two copies serve all strategies.
      C = x;
      L.assign(x.rbegin(), x.rend());
      for (int i = 0; i <= k; ++i) {
        C[i].pdf_fwd = cam[i];
        C[i].pdf_rev = lig[i];
        L[i].pdf_fwd = lig[k - i];
        L[i].pdf_rev = cam[k - i];
      }
      float sum = 0;
      for (int t2 = 1; t2 <= k + 1; ++t2) {
        const int s2 = k + 1 - t2;
        if (s2 + t2 - 2 > max_depth() || (s2 == 1 && t2 == 1)) continue;
        if (s2 > s_.max_light_length || t2 - 1 > camera_depth()) continue;  // the subpath limits exclude it
        std::vector<PathVertex>&c2 = C, &l2 = L;
        // Only strategies whose connection can be made sample this path.
        if (t2 >= 1 && s2 >= 1) {
          const PathVertex& a = c2[t2 - 1];
          const PathVertex& b = l2[s2 - 1];
          bool a_ok = a.type == VertexType::Camera ? ctx_.camera.connectable() : (scatters(a) && !a.delta);
          bool b_ok = b.type == VertexType::Light ? !b.delta_direction : (scatters(b) && !b.delta);
          if (!a_ok || !b_ok) continue;
        }
        if (s2 == 0 && is_delta_light(x[k])) continue;
        // Nor do strategies whose walks cannot reach one of its vertices (a zero density not
        // due to a delta vertex sampling it): the frames of a vertex differ with the direction
        // a walk arrives from (Bdpt::view_frame).
        bool reaches = true;
        for (int i = 2; i < t2 && reaches; ++i) reaches = cam[i] != 0 || x[i - 1].delta;
        for (int i = t2; i < k && reaches; ++i) reaches = lig[i] != 0 || x[i + 1].delta;
        if (!reaches) continue;
        if (t2 == 1 && (x[1].delta || split_)) continue;  // none where the camera ray meets a catcher
        const PathVertex* sampled = s2 == 1 ? &l2[0] : (t2 == 1 ? &c2[0] : nullptr);
        PathVertex sampled_copy;
        if (sampled) sampled_copy = *sampled;
        float w = mis_weight(l2, c2, sampled ? &sampled_copy : nullptr, s2, t2, pixel_center_);
        if (!(w >= 0 && w <= 1 + 1e-5f)) sum = NAN;  // a weight outside [0, 1] fails the check
        if (s2 == 0 && t2 >= 3) {
          // The same weight with the emitter off the subpath, as one the camera walk crossed
          // (add_emitters_reached): the vertex in its place and the reverse density of the vertex
          // before its predecessor are the walk's, towards another vertex; mis_weight must not
          // read them.
          PathVertex emitter = c2[t2 - 1];
          c3.assign(c2.begin(), c2.begin() + t2);
          c3[t2 - 1].p = c3[t2 - 1].p + Vec3(1.0f);
          c3[t2 - 1].pdf_fwd = c3[t2 - 1].pdf_rev = NAN;
          c3[t2 - 3].pdf_rev = 2 * c3[t2 - 3].pdf_rev + 1;
          const float w_crossed = mis_weight(l2, c3, &emitter, 0, t2, pixel_center_);
          if (!(std::abs(w_crossed - w) <= 1e-5f * std::max(1.0f, w))) sum = NAN;
        }
        sum += w * kind_limit_factor(l2, c2, s2, t2) / factor;
      }
      sums.push_back(sum);
    }
  return sums;
}

std::vector<float> bdpt_mis_weight_sums(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler) {
  SampleStats stats;
  Bdpt b(ctx, cs, sampler, stats);
  return b.weight_sums();
}

}  // namespace lt
