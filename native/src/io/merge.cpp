// lt_merge_exr: sample-split parts of one render into the render itself. A part of samples
// [a, b) holds per pixel the mean of its c samples (c from SampleCount.X) and, for bidirectional
// renders, the light-tracing splats divided by its own light-path count (b - a per pixel), so the
// count-weighted mean of the parts is the mean over all their samples, exactly up to float rounding.
#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "io/exr.h"

namespace lt {

namespace {

struct Range { long long begin, end; size_t part; };

// The attributes that say which render a part belongs to: parts must agree on each.
const char* const kIdentity[] = {"lantern/scene", "lantern/seed", "lantern/integrator", "lantern/resolution",
                                 "lantern/region"};

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

std::string channel_list(const ExrImage& img) {
  std::string s;
  for (const ExrChannel& c : img.channels) s += (s.empty() ? "" : " ") + c.name;
  return s;
}

}  // namespace

std::string merge_exr(const std::string& out_path, const std::vector<std::string>& paths) {
  if (paths.empty()) throw InvalidArgument("merge: no parts given");
  std::vector<ExrImage> parts;
  for (const std::string& p : paths) parts.push_back(read_exr(p));

  // Every part must carry its sample counts, and agree with the first on what was rendered.
  std::vector<Range> ranges;
  std::vector<long long> samples(parts.size());
  for (size_t i = 0; i < parts.size(); ++i) {
    const ExrImage& img = parts[i];
    const std::string& path = paths[i];
    auto s = img.attributes.find("lantern/samples");
    auto r = img.attributes.find("lantern/sample_ranges");
    if (s == img.attributes.end() || r == img.attributes.end() || !img.find("SampleCount.X"))
      throw InvalidArgument(path + ": no recorded sample counts (needs the lantern/samples and lantern/sample_ranges "
                            "header attributes and the SampleCount.X channel that Lantern writes); not merged");
    samples[i] = std::atoll(s->second.c_str());
    std::vector<Range> own = parse_ranges(r->second, i, path);
    long long total = 0;
    for (const Range& x : own) total += x.end - x.begin;
    if (total != samples[i] || samples[i] <= 0)
      throw InvalidArgument(path + ": lantern/samples (" + s->second + ") does not match lantern/sample_ranges (" +
                            r->second + ")");
    ranges.insert(ranges.end(), own.begin(), own.end());
    if (i == 0) continue;
    const ExrImage& ref = parts[0];
    for (const char* key : kIdentity) {
      auto a = ref.attributes.find(key), b = img.attributes.find(key);
      const std::string va = a == ref.attributes.end() ? "(none)" : a->second;
      const std::string vb = b == img.attributes.end() ? "(none)" : b->second;
      if (va != vb)
        throw InvalidArgument(std::string(key + 8) + " differs: " + paths[0] + " has " + va + ", " + path + " has " + vb +
                              "; parts of different renders cannot be merged");
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

  const ExrImage& ref = parts[0];
  const size_t n = size_t(ref.width) * ref.height, np = parts.size();
  auto channel = [&](size_t part, const std::string& name) { return parts[part].find(name)->pixels.data(); };
  long long total_samples = 0;
  for (long long s : samples) total_samples += s;
  const bool light = ref.find("LightTracing.R") != nullptr;

  std::vector<ExrChannel> out;
  for (const ExrChannel& c : ref.channels) out.push_back({c.name, std::vector<float>(n)});
  auto out_channel = [&](const std::string& name) {
    for (ExrChannel& c : out)
      if (c.name == name) return c.pixels.data();
    return static_cast<float*>(nullptr);
  };
  std::vector<const float*> counts(np);
  for (size_t p = 0; p < np; ++p) counts[p] = channel(p, "SampleCount.X");
  const char* const rgb[3] = {"R", "G", "B"};

  for (ExrChannel& oc : out) {
    const std::string& name = oc.name;
    const bool is_rgb = name == "R" || name == "G" || name == "B";
    if (name.rfind("Variance.", 0) == 0 || (is_rgb && light)) continue;  // below, with their means
    std::vector<const float*> in(np);
    for (size_t p = 0; p < np; ++p) in[p] = channel(p, name);
    for (size_t i = 0; i < n; ++i) {
      double v;
      if (name == "SampleCount.X") {
        v = 0;
        for (size_t p = 0; p < np; ++p) v += in[p][i];
      } else if (name == "Depth.Z") {  // the nearest hit over all samples
        v = in[0][i];
        for (size_t p = 1; p < np; ++p) v = std::min(v, double(in[p][i]));
      } else if (name.rfind("LightTracing.", 0) == 0) {  // splats over light paths: b - a per pixel
        v = 0;
        for (size_t p = 0; p < np; ++p) v += double(samples[p]) * in[p][i];
        v /= double(total_samples);
      } else {  // a per-sample mean: weighted by the pixel's sample counts
        double sum = 0, c = 0;
        for (size_t p = 0; p < np; ++p) {
          sum += double(counts[p][i]) * in[p][i];
          c += counts[p][i];
        }
        v = c > 0 ? sum / c : 0.0;
      }
      oc.pixels[i] = float(v);
    }
  }
  // Combined's camera part (Combined minus LightTracing) and its variance, pooled over the parts
  // (Chan et al. 1979): SS = sum_p [(c_p - 1) s_p^2 + c_p (m_p - M)^2], with s_p^2 = c_p Var_p since
  // the Variance pass is the variance of the pixel mean, s^2 / c.
  for (int k = 0; k < 3; ++k) {
    const std::string cn = rgb[k], vn = std::string("Variance.") + rgb[k], ln = std::string("LightTracing.") + rgb[k];
    float* merged_mean = out_channel(cn);
    float* merged_var = out_channel(vn);
    const float* merged_light = light ? out_channel(ln) : nullptr;
    std::vector<double> m(np);
    for (size_t i = 0; i < n; ++i) {
      double c = 0, sum = 0;
      for (size_t p = 0; p < np; ++p) {
        m[p] = double(channel(p, cn)[i]) - (light ? double(channel(p, ln)[i]) : 0.0);
        c += counts[p][i];
        sum += counts[p][i] * m[p];
      }
      const double mean = c > 0 ? sum / c : 0.0;
      if (light && merged_mean) merged_mean[i] = float(mean + merged_light[i]);
      if (!merged_var) continue;
      double ss = 0;
      for (size_t p = 0; p < np; ++p) {
        const double cp = counts[p][i];
        ss += (cp - 1 > 0 ? (cp - 1) * cp * double(channel(p, vn)[i]) : 0.0) + cp * (m[p] - mean) * (m[p] - mean);
      }
      merged_var[i] = float(c > 1 ? ss / ((c - 1) * c) : 0.0);
    }
  }

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
  attrs["lantern/render_seconds"] = std::to_string(seconds);
  attrs["lantern/merged_parts"] = std::to_string(np);
  write_exr(out_path, ref.width, ref.height, out, attrs);
  return "merged " + std::to_string(np) + " parts into " + out_path + ": " + std::to_string(total_samples) +
         " samples (" + attrs["lantern/sample_ranges"] + ")";
}

}  // namespace lt
