// lt_merge_exr: sample-split parts of one render into the render itself. A part of samples
// [a, b) holds per pixel the mean of its c samples (c from SampleCount.X) and, for bidirectional
// renders, the light-tracing splats divided by its own light-path count (lantern/light_paths: one per
// camera sample traced, fewer with adaptive sampling or a cut pass), so the count-weighted mean of
// the parts is the mean over all their samples, exactly up to float rounding.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/cryptomatte.h"
#include "core/error.h"
#include "core/film.h"
#include "io/exr.h"

namespace lt {

namespace {

struct Range {
  long long begin, end;
  size_t part;
};

// The attributes that say which render a part belongs to: parts must agree on each.
const char* const kIdentity[] = {"lantern/scene",      "lantern/seed",   "lantern/integrator",
                                 "lantern/resolution", "lantern/region", "lantern/sample_pattern"};

std::vector<Range> parse_ranges(const std::string& text, size_t part, const std::string& path) {
  std::vector<Range> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    long long a = std::strtoll(item.c_str(), &end, 10);
    long long b = *end == '-' ? std::strtoll(end + 1, &end, 10) : -1;
    if (*end != '\0' || a < 0 || b < a)
      throw InvalidArgument(path + ": unreadable sample range \"" + item + "\" in lantern/sample_ranges");
    if (b > a) out.push_back({a, b, part});
  }
  return out;
}

std::string join_ranges(std::vector<Range> r) {
  std::sort(r.begin(), r.end(), [](const Range& x, const Range& y) { return x.begin < y.begin; });
  std::string out;
  for (size_t i = 0; i < r.size();) {
    long long a = r[i].begin, b = r[i].end;
    for (++i; i < r.size() && r[i].begin == b; ++i) b = r[i].end;  // adjacent ranges read as one
    out += (out.empty() ? "" : ",") + std::to_string(a) + "-" + std::to_string(b);
  }
  return out;
}

// Combined (R, G, B, A) and the Shadow Catcher pass of merged shadow catcher means (film.h's
// CatcherPart channels), as the film reads them.
void recompute_catcher_passes(const ExrImage& ref, const std::vector<double>& count, std::vector<ExrChannel>* out) {
  auto merged = [&](const std::string& name) -> std::vector<float>* {
    for (ExrChannel& ch : *out)
      if (ch.name == name) return &ch.pixels;
    return nullptr;
  };
  const auto mode = ref.attributes.find("lantern/shadow_catcher");
  const auto transparent = ref.attributes.find("lantern/transparent");
  const bool approximate = mode != ref.attributes.end() && mode->second == "approximate";
  const bool transparent_film = transparent != ref.attributes.end() && transparent->second == "1";
  std::vector<const std::vector<float>*> in[kCatcherParts];
  for (int part = 0; part < kCatcherParts; ++part)
    for (const char* c = catcher_part_letters(part); *c; ++c) {
      const std::vector<float>* v = merged(std::string(catcher_part_name(part)) + "." + *c);
      if (!v)
        throw InvalidArgument(std::string("the shadow catcher channels lack ") + catcher_part_name(part) + "." + *c);
      in[part].push_back(v);
    }
  std::vector<float>* combined[4] = {merged("R"), merged("G"), merged("B"), merged("A")};
  std::vector<float>* pass[3] = {merged("ShadowCatcher.R"), merged("ShadowCatcher.G"), merged("ShadowCatcher.B")};
  // BDPT's splats, merged over the light paths (CatcherPixel::splat).
  std::vector<float>* splat[3] = {merged("LightTracing.R"), merged("LightTracing.G"), merged("LightTracing.B")};
  for (size_t i = 0; i < count.size(); ++i) {
    CatcherPixel m;
    for (int k = 0; k < 3; ++k) {
      m.combined[k] = (*in[kCatcherCombined][k])[i];
      m.catcher[k] = (*in[kCatcherLight][k])[i];
      m.background[k] = (*in[kCatcherBackground][k])[i];
    }
    m.alpha = (*in[kCatcherCombined][3])[i];
    for (int k = 0; k < 4; ++k) m.matte[k] = (*in[kCatcherMatte][k])[i];
    m.split = (*in[kCatcherSplit][0])[i];
    for (int k = 0; k < 3; ++k) m.splat[k] = splat[k] ? (*splat[k])[i] : 0.0;
    float rgba[4] = {0, 0, 0, 0};
    if (count[i] > 0) catcher_combined(m, approximate, transparent_film, rgba);
    for (int k = 0; k < 4; ++k)
      if (combined[k]) (*combined[k])[i] = rgba[k];
    double sc[3];
    catcher_pass(m, sc);
    for (int k = 0; k < 3; ++k)
      if (pass[k]) (*pass[k])[i] = float(sc[k]);
  }
}

std::string channel_list(const ExrImage& img) {
  std::string s;
  for (const ExrChannel& c : img.channels) s += (s.empty() ? "" : " ") + c.name;
  return s;
}

}  // namespace

std::string merge_exr(const std::string& out_path, const std::vector<std::string>& paths) {
  if (paths.empty()) throw InvalidArgument("merge: no parts given");
  // The output is written last, over whatever is there: never over one of the parts (also through
  // a symbolic or hard link, or another spelling of the path).
  std::error_code ec;
  for (const std::string& p : paths)
    if (std::filesystem::equivalent(out_path, p, ec) ||
        std::filesystem::weakly_canonical(out_path, ec) == std::filesystem::weakly_canonical(p, ec))
      throw InvalidArgument("merge: the output " + out_path + " is also a part (" + p +
                            "); merging would overwrite it: give another output path");
  // Headers first: everything is checked before any pixel is read or anything written.
  std::vector<ExrImage> parts;
  for (const std::string& p : paths) parts.push_back(read_exr(p, false));

  // Every part must carry its sample counts, and agree with the first on what was rendered.
  std::vector<Range> ranges;
  std::vector<long long> samples(parts.size()), light_paths(parts.size(), 0), first_sample(parts.size());
  for (size_t i = 0; i < parts.size(); ++i) {
    const ExrImage& img = parts[i];
    const std::string& path = paths[i];
    auto s = img.attributes.find("lantern/samples");
    auto r = img.attributes.find("lantern/sample_ranges");
    if (s == img.attributes.end() || r == img.attributes.end() || !img.find("SampleCount.X"))
      throw InvalidArgument(path +
                            ": no recorded sample counts (needs the lantern/samples and lantern/sample_ranges "
                            "header attributes and the SampleCount.X channel that Lantern writes); not merged");
    samples[i] = std::atoll(s->second.c_str());
    std::vector<Range> own = parse_ranges(r->second, i, path);
    first_sample[i] = own.empty() ? 0 : own.front().begin;
    for (const Range& x : own) first_sample[i] = std::min(first_sample[i], x.begin);
    long long total = 0;
    for (const Range& x : own) total += x.end - x.begin;
    if (samples[i] <= 0)
      throw InvalidArgument(path + ": the part has no samples (a render cancelled before its first)");
    if (total != samples[i])
      throw InvalidArgument(path + ": lantern/samples (" + s->second + ") does not match lantern/sample_ranges (" +
                            r->second + ")");
    ranges.insert(ranges.end(), own.begin(), own.end());
    if (img.find("LightTracing.R")) {
      auto l = img.attributes.find("lantern/light_paths");
      light_paths[i] = l == img.attributes.end() ? 0 : std::atoll(l->second.c_str());
      if (light_paths[i] <= 0)
        throw InvalidArgument(path + ": light-tracing channels without a lantern/light_paths count; not merged");
    }
    if (i == 0) continue;
    const ExrImage& ref = parts[0];
    for (const char* key : kIdentity) {
      auto a = ref.attributes.find(key), b = img.attributes.find(key);
      const std::string va = a == ref.attributes.end() ? "(none)" : a->second;
      const std::string vb = b == img.attributes.end() ? "(none)" : b->second;
      if (va != vb)
        throw InvalidArgument(std::string(key + 8) + " differs: " + paths[0] + " has " + va + ", " + path + " has " +
                              vb + "; parts of different renders cannot be merged");
    }
    // Cryptomatte manifests name the ids: parts of one scene carry the same ones.
    for (const ExrImage* a : {&ref, &img})
      for (const auto& [key, value] : a->attributes) {
        if (key.rfind("cryptomatte/", 0) != 0) continue;
        auto x = ref.attributes.find(key), y = img.attributes.find(key);
        if (x == ref.attributes.end() || y == img.attributes.end() || x->second != y->second)
          throw InvalidArgument(key + " differs between " + paths[0] + " and " + path +
                                "; parts with different Cryptomatte manifests cannot be merged");
      }
    if (img.width != ref.width || img.height != ref.height)
      throw InvalidArgument("resolution differs: " + paths[0] + " is " + std::to_string(ref.width) + "x" +
                            std::to_string(ref.height) + ", " + path + " is " + std::to_string(img.width) + "x" +
                            std::to_string(img.height));
    if (channel_list(img) != channel_list(ref))
      throw InvalidArgument("passes differ: " + paths[0] + " has [" + channel_list(ref) + "], " + path + " has [" +
                            channel_list(img) + "]");
  }
  std::sort(ranges.begin(), ranges.end(), [](const Range& x, const Range& y) { return x.begin < y.begin; });
  for (size_t k = 1; k < ranges.size(); ++k)
    if (ranges[k].begin < ranges[k - 1].end)
      throw InvalidArgument("sample ranges overlap: " + paths[ranges[k - 1].part] + " has samples [" +
                            std::to_string(ranges[k - 1].begin) + ", " + std::to_string(ranges[k - 1].end) + "), " +
                            paths[ranges[k].part] + " has [" + std::to_string(ranges[k].begin) + ", " +
                            std::to_string(ranges[k].end) + "); the same samples would count twice");

  // Then one part at a time into double accumulators (memory: the accumulators and one part).
  // Per pixel and part p with c_p samples: means weighted by c_p; Depth the minimum; LightTracing
  // (splats over the part's light paths) weighted by its light paths; Combined's
  // camera part (Combined - LightTracing) with its sum of squared deviations pooled by Chan et
  // al.'s update (1979), from ss_p = (c_p - 1) c_p Var_p since the Variance pass is s^2 / c.
  const ExrImage& ref = parts[0];
  const size_t n = size_t(ref.width) * ref.height, nc = ref.channels.size(), np = parts.size();
  // Light tracing's splats: all three colour channels or none (fuzz_exr_merge: one alone was read
  // through a null channel).
  int light_channels = 0;
  for (int c = 0; c < 3; ++c) light_channels += ref.find(std::string("LightTracing.") + "RGB"[c]) != nullptr;
  if (light_channels % 3 != 0)
    throw InvalidArgument(paths[0] + ": " + std::to_string(light_channels) +
                          " of the LightTracing R, G and B channels; not merged");
  const bool light = light_channels == 3;
  const bool catcher = ref.find(std::string(catcher_part_name(kCatcherCombined)) + ".R") != nullptr;
  long long total_samples = 0, total_light_paths = 0;
  for (long long s : samples) total_samples += s;
  for (long long l : light_paths) total_light_paths += l;
  // Divided: a light pass read divided by its Colour (film.h), merged as the mean of Direct x
  // Colour divided by the merged Colour; with BDPT each light pass's splat part comes apart
  // (LightTracing.<pass>), weighted by the light paths as Combined's; First: the pixel's first
  // sample's value (Position and the indices), from the part with the lowest sample index.
  // Crypto: a Cryptomatte layer's channel (CryptoObject00.r, ...), merged per type below.
  // Covered: a mean over the samples that wrote a value (Vector), weighted by the part's samples
  // times its share of them (VectorCoverage.X, itself a Mean).
  enum Kind { Mean, Count, Depth, Light, Variance, CombinedRGB, Divided, First, SplitMean, Crypto, Covered };
  std::vector<Kind> kind(nc);
  std::vector<int> rgb_index(nc, -1);
  // Divided channels: the channels of their pass and of its Colour, in RGB order.
  std::vector<std::array<int, 3>> self_k(nc, {-1, -1, -1}), colour_k(nc, {-1, -1, -1});
  std::vector<int> split_k(nc, -1);  // a light pass's LightTracing.<pass> channel
  const int coverage_k = [&] {
    for (size_t k = 0; k < nc; ++k)
      if (ref.channels[k].name == "VectorCoverage.X") return int(k);
    return -1;
  }();
  auto channel_index = [&](const std::string& name) {
    for (size_t k = 0; k < nc; ++k)
      if (ref.channels[k].name == name) return int(k);
    return -1;
  };
  for (size_t k = 0; k < nc; ++k) {
    const std::string& name = ref.channels[k].name;
    kind[k] = name == "SampleCount.X"               ? Count
              : name == "Depth.Z"                   ? Depth
              : name.rfind("LightTracing.", 0) == 0 ? Light
              : name.rfind("Variance.", 0) == 0     ? Variance
                                                    : Mean;
    for (int c = 0; c < 3; ++c)
      if (name == std::string(1, "RGB"[c]))
        kind[k] = CombinedRGB, rgb_index[k] = c;
      else if (kind[k] == Variance && name == std::string("Variance.") + "RGB"[c])
        rgb_index[k] = c;
    for (int pass = kFirstSummedPass; pass < int(Pass::Count); ++pass) {
      const std::string prefix = std::string(exr_pass_name(Pass(pass))) + ".";
      if (name.rfind(prefix, 0) != 0) continue;
      const Pass colour = light_pass_color(Pass(pass));
      if (Pass(pass) == Pass::Position || Pass(pass) == Pass::ObjectIndex || Pass(pass) == Pass::MaterialIndex)
        kind[k] = First;
      if (Pass(pass) == Pass::Vector) {
        if (coverage_k < 0)
          throw InvalidArgument(paths[0] + ": " + name +
                                " without VectorCoverage.X, which it is weighted by; not merged");
        kind[k] = Covered;
      }
      split_k[k] = channel_index("LightTracing." + name);
      if (split_k[k] >= 0 && colour == Pass::Count) kind[k] = SplitMean;
      if (colour == Pass::Count) continue;
      for (int c = 0; c < 3; ++c) {
        self_k[k][c] = channel_index(prefix + "RGB"[c]);
        colour_k[k][c] = channel_index(std::string(exr_pass_name(colour)) + "." + "RGB"[c]);
        if (name == prefix + "RGB"[c]) rgb_index[k] = c;
      }
      // The division needs the pass's three channels and its Colour's (fuzz_exr_merge: one
      // missing was read at index -1).
      const auto all = [](const std::array<int, 3>& ks) { return ks[0] >= 0 && ks[1] >= 0 && ks[2] >= 0; };
      if (!all(colour_k[k]) || rgb_index[k] < 0)
        throw InvalidArgument(paths[0] + ": " + name + " without its " + exr_pass_name(colour) +
                              " channels, which it is divided by; not merged");
      if (!all(self_k[k]))
        throw InvalidArgument(paths[0] + ": " + name + " without the other channels of " +
                              prefix.substr(0, prefix.size() - 1) + ", with which it is divided; not merged");
      kind[k] = Divided;
    }
    // Any other mean with its splats' part apart (light groups' Combined_<name>): as a light pass.
    if (kind[k] == Mean && (split_k[k] = channel_index("LightTracing." + name)) >= 0) kind[k] = SplitMean;
  }
  // Cryptomatte: per type, its layers' channels (r, g, b, a = id, coverage, id, coverage).
  std::vector<std::array<int, 4>> crypto_k[kCryptoTypes];
  for (int t = 0; t < kCryptoTypes; ++t)
    for (int layer = 0;; ++layer) {
      char prefix[32];
      std::snprintf(prefix, sizeof prefix, "%s%02d.", cryptomatte_type_name(t), layer);
      std::array<int, 4> ks;
      for (int c = 0; c < 4; ++c) ks[c] = channel_index(std::string(prefix) + "rgba"[c]);
      if (ks[0] < 0 || ks[1] < 0 || ks[2] < 0 || ks[3] < 0) break;
      for (int c = 0; c < 4; ++c) kind[ks[c]] = Crypto;
      crypto_k[t].push_back(ks);
    }
  // Per type and pixel, up to twice a part's slots of (id, coverage x the part's sample count),
  // the sums of the ids' weights (an id past them is dropped as the film drops one: the merge is
  // exact while a pixel's parts name no more ids than that, and its output keeps half of them).
  std::vector<float> crypto_acc[kCryptoTypes];
  auto crypto_capacity = [&](int t) { return 4 * int(crypto_k[t].size()); };
  for (int t = 0; t < kCryptoTypes; ++t) crypto_acc[t].assign(2 * size_t(crypto_capacity(t)) * n, 0.0f);
  int light_k[3] = {-1, -1, -1};
  for (size_t k = 0; k < nc; ++k)
    for (int c = 0; c < 3; ++c)
      if (ref.channels[k].name == std::string("LightTracing.") + "RGB"[c]) light_k[c] = int(k);
  std::vector<std::vector<double>> acc(nc);
  for (size_t k = 0; k < nc; ++k)
    if (kind[k] != Crypto) acc[k].assign(n, 0.0);
  std::vector<double> count(n, 0.0);
  // First: the sample index its value came from, per pixel (the lowest wins).
  std::vector<long long> first_from(n, std::numeric_limits<long long>::max());
  // Per pixel and colour channel: running count-weighted camera mean and squared deviations.
  std::vector<double> cam_mean(n * 3, 0.0), cam_ss(n * 3, 0.0);
  for (size_t p = 0; p < np; ++p) {
    const ExrImage img = read_exr(paths[p]);
    if (channel_list(img) != channel_list(ref)) throw IoError(paths[p] + " changed while merging");
    const float* c_p = img.find("SampleCount.X")->pixels.data();
    // With shadow catchers R, G, B are the matte (film.h): Combined's own means pool the variance.
    const std::string rgb_prefix = catcher ? std::string(catcher_part_name(kCatcherCombined)) + "." : "";
    const float* rgb[3] = {};
    for (int c = 0; c < 3; ++c)
      if (const ExrChannel* ch = img.find(rgb_prefix + "RGB"[c])) rgb[c] = ch->pixels.data();
    const float* lt[3] = {};
    const float* var[3] = {};
    for (int c = 0; c < 3; ++c) {
      if (light) lt[c] = img.find(std::string("LightTracing.") + "RGB"[c])->pixels.data();
      if (const ExrChannel* v = img.find(std::string("Variance.") + "RGB"[c])) var[c] = v->pixels.data();
    }
    for (size_t k = 0; k < nc; ++k) {
      const float* in = img.channels[k].pixels.data();
      double* a = acc[k].data();
      switch (kind[k]) {
        case Mean:
          for (size_t i = 0; i < n; ++i) a[i] += double(c_p[i]) * in[i];
          break;
        case Count:
          for (size_t i = 0; i < n; ++i) a[i] += in[i];
          break;
        case Depth:
          for (size_t i = 0; i < n; ++i) a[i] = p == 0 ? in[i] : std::min(a[i], double(in[i]));
          break;
        case Light:
          for (size_t i = 0; i < n; ++i) a[i] += double(light_paths[p]) * in[i];
          break;
        case Divided: {
          // The camera samples' part: Direct x Colour less the splats' (none where the part's
          // Colour is zero: camera samples there met no closure of the kind).
          const float* col = img.channels[colour_k[k][rgb_index[k]]].pixels.data();
          const float* lt = split_k[k] >= 0 ? img.channels[split_k[k]].pixels.data() : nullptr;
          for (size_t i = 0; i < n; ++i)
            if (col[i] != 0) a[i] += double(c_p[i]) * (double(in[i]) * col[i] - (lt ? lt[i] : 0.0));
          break;
        }
        case SplitMean: {
          const float* lt = img.channels[split_k[k]].pixels.data();
          for (size_t i = 0; i < n; ++i) a[i] += double(c_p[i]) * (double(in[i]) - lt[i]);
          break;
        }
        case First:
          for (size_t i = 0; i < n; ++i)
            if (c_p[i] > 0 && first_sample[p] < first_from[i]) a[i] = in[i];
          break;
        case Covered: {
          const float* cov = img.channels[coverage_k].pixels.data();
          for (size_t i = 0; i < n; ++i) a[i] += double(c_p[i]) * cov[i] * in[i];
          break;
        }
        case Variance:
        case CombinedRGB:
        case Crypto:
          break;  // below
      }
    }
    // Cryptomatte: coverage is a mean over the part's samples, so c_p x coverage sums its weights.
    for (int t = 0; t < kCryptoTypes; ++t)
      for (const std::array<int, 4>& ks : crypto_k[t])
        for (int pair = 0; pair < 2; ++pair) {
          const float* id = img.channels[ks[2 * pair]].pixels.data();
          const float* cov = img.channels[ks[2 * pair + 1]].pixels.data();
          const int cap = crypto_capacity(t);
          for (size_t i = 0; i < n; ++i)
            if (id[i] != 0.0f && c_p[i] > 0)
              cryptomatte_add(&crypto_acc[t][2 * size_t(cap) * i], cap, id[i], c_p[i] * cov[i]);
        }
    for (int c = 0; c < 3; ++c) {
      if (!rgb[c]) continue;
      for (size_t i = 0; i < n; ++i) {
        const double cp = c_p[i];
        if (cp <= 0) continue;
        // The camera samples' mean: Combined less the splats (CatcherCombined holds none).
        const double m = double(rgb[c][i]) - (light && !catcher ? double(lt[c][i]) : 0.0);
        const double ss = var[c] && cp > 1 ? (cp - 1) * cp * double(var[c][i]) : 0.0;
        const double before = count[i], after = before + cp, delta = m - cam_mean[3 * i + c];
        cam_mean[3 * i + c] += delta * cp / after;
        cam_ss[3 * i + c] += ss + delta * delta * before * cp / after;
      }
    }
    for (size_t i = 0; i < n; ++i) {
      count[i] += c_p[i];
      if (c_p[i] > 0) first_from[i] = std::min(first_from[i], first_sample[p]);
    }
  }

  // Cryptomatte: per pixel the ids of largest merged coverage, as many as a part's slots.
  std::vector<std::vector<float>> crypto_out(nc);
  for (int t = 0; t < kCryptoTypes; ++t) {
    const int slots = 2 * int(crypto_k[t].size());
    if (!slots) continue;
    for (const std::array<int, 4>& ks : crypto_k[t])
      for (int k : ks) crypto_out[k].assign(n, 0.0f);
    const int cap = crypto_capacity(t);
    std::vector<float> ids(cap), pairs(2 * size_t(slots));
    std::vector<double> weights(cap);
    for (size_t i = 0; i < n; ++i) {
      const float* e = &crypto_acc[t][2 * size_t(cap) * i];
      for (int j = 0; j < cap; ++j) {
        ids[j] = e[2 * j];
        weights[j] = count[i] > 0 ? e[2 * j + 1] / count[i] : 0.0;
      }
      cryptomatte_top(ids.data(), weights.data(), cap, slots, pairs.data());
      for (int s = 0; s < slots; ++s) {
        const std::array<int, 4>& ks = crypto_k[t][s / 2];
        crypto_out[ks[2 * (s % 2)]][i] = pairs[2 * s];
        crypto_out[ks[2 * (s % 2) + 1]][i] = pairs[2 * s + 1];
      }
    }
    std::vector<float>().swap(crypto_acc[t]);
  }

  std::vector<ExrChannel> out;
  for (size_t k = 0; k < nc; ++k) {
    if (kind[k] == Crypto) {
      out.push_back({ref.channels[k].name, std::move(crypto_out[k])});
      continue;
    }
    ExrChannel oc{ref.channels[k].name, std::vector<float>(n)};
    const double* a = acc[k].data();
    for (size_t i = 0; i < n; ++i) {
      double v = 0;
      switch (kind[k]) {
        case Mean:
          v = count[i] > 0 ? a[i] / count[i] : 0.0;
          break;
        case SplitMean:
          v = (count[i] > 0 ? a[i] / count[i] : 0.0) + acc[split_k[k]][i] / double(total_light_paths);
          break;
        case Count:
        case Depth:
        case First:
          v = a[i];
          break;
        case Covered:
          v = acc[coverage_k][i] > 0 ? a[i] / acc[coverage_k][i] : 0.0;
          break;
        case Divided: {
          if (!(count[i] > 0)) break;
          double raw[3], colour[3];
          float o[3];
          for (int c = 0; c < 3; ++c) {
            raw[c] = acc[self_k[k][c]][i] / count[i];
            if (split_k[self_k[k][c]] >= 0) raw[c] += acc[split_k[self_k[k][c]]][i] / double(total_light_paths);
            colour[c] = acc[colour_k[k][c]][i] / count[i];
          }
          divide_even_color(raw, colour, o);
          v = o[rgb_index[k]];
          break;
        }
        case Light:
          v = a[i] / double(total_light_paths);
          break;
        case CombinedRGB: {
          const int c = rgb_index[k];
          v = cam_mean[3 * i + c];
          if (light) v += acc[light_k[c]][i] / double(total_light_paths);
          break;
        }
        case Crypto:
          break;  // above
        case Variance: {
          const int c = rgb_index[k];
          v = c >= 0 && count[i] > 1 ? cam_ss[3 * i + c] / ((count[i] - 1) * count[i]) : 0.0;
          break;
        }
      }
      oc.pixels[i] = float(v);
    }
    out.push_back(std::move(oc));
  }

  // Shadow catchers: Combined and the Shadow Catcher pass again from the merged means (film.h).
  if (catcher) recompute_catcher_passes(ref, count, &out);

  // Header: what all parts agree on, then the merged counts.
  std::map<std::string, std::string> attrs;
  double seconds = 0;
  for (const auto& [k, v] : ref.attributes) {
    bool same = true;
    for (size_t p = 1; p < np && same; ++p) {
      auto it = parts[p].attributes.find(k);
      same = it != parts[p].attributes.end() && it->second == v;
    }
    if (same) attrs[k] = v;
  }
  for (const ExrImage& img : parts) {
    auto it = img.attributes.find("lantern/render_seconds");
    if (it != img.attributes.end()) seconds += std::atof(it->second.c_str());
  }
  attrs["lantern/samples"] = std::to_string(total_samples);
  attrs["lantern/sample_ranges"] = join_ranges(ranges);
  if (light) attrs["lantern/light_paths"] = std::to_string(total_light_paths);
  attrs["lantern/render_seconds"] = std::to_string(seconds);
  attrs["lantern/merged_parts"] = std::to_string(np);
  write_exr(out_path, ref.width, ref.height, out, attrs);
  return "merged " + std::to_string(np) + " parts into " + out_path + ": " + std::to_string(total_samples) +
         " samples (" + attrs["lantern/sample_ranges"] + ")";
}

}  // namespace lt
