// Raw Embree 3 ray-rate baseline for the throughput benchmark (bench/cornell_throughput.py).
//
// Loads world-space triangles, a pinhole camera and an area-light quad dumped from Blender
// (format below), builds one Embree scene and traces a fixed number of rays with rtcIntersect1 /
// rtcOccluded1 on N threads (std::thread), in a pattern that resembles a path tracer: per pixel
// sample a jittered primary ray, then at every hit one shadow ray to a random point of the light
// (rtcOccluded1, unless --mode closest) and one cosine-distributed bounce ray (rtcIntersect1), up
// to --max-depth bounces with Russian roulette (q = --rr) from bounce 3. No shading, no film: this
// is the rate Embree alone reaches on this scene, the ceiling for Lantern's rays per second.
//
// Scene file (little endian):
//   char magic[4] = "LTRB"; int32 version = 1; int32 vertex_count, triangle_count, width, height
//   float32 camera[15]   origin xyz, then the image-plane corners (world space) for the pixel
//                        corners (0,0) top-left, (W,0) top-right, (0,H) bottom-left, (W,H) bottom-right
//   float32 light[12]    the area light's four corners (world space), in order around the quad
//   float32 vertices[3 * vertex_count]; int32 indices[3 * triangle_count]
//   int32 object[triangle_count]  the object each triangle came from (for --two-level)
//
// Output: one JSON object on stdout.
#include <embree3/rtcore.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <string>
#include <thread>
#include <vector>

namespace {

struct V3 {
  float x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline V3 normalize(V3 a) { return a * (1.0f / std::sqrt(dot(a, a))); }

// PCG32 (O'Neill), one stream per work chunk.
struct Rng {
  uint64_t state;
  explicit Rng(uint64_t seed) : state(seed * 6364136223846793005ULL + 1442695040888963407ULL) { next(); }
  uint32_t next() {
    uint64_t old = state;
    state = old * 6364136223846793005ULL + 1442695040888963407ULL;
    uint32_t xs = uint32_t(((old >> 18u) ^ old) >> 27u), rot = uint32_t(old >> 59u);
    return (xs >> rot) | (xs << ((-rot) & 31));
  }
  float uniform() { return float(next() >> 8) * (1.0f / 16777216.0f); }
};

struct SceneFile {
  int width = 0, height = 0;
  float camera[15];
  float light[12];
  std::vector<float> vertices;
  std::vector<int32_t> indices, object;
};

bool read_scene(const char* path, SceneFile* s) {
  FILE* f = std::fopen(path, "rb");
  if (!f) return false;
  char magic[4];
  int32_t head[5];
  bool ok = std::fread(magic, 1, 4, f) == 4 && std::memcmp(magic, "LTRB", 4) == 0 && std::fread(head, 4, 5, f) == 5 &&
            head[0] == 1;
  if (ok) {
    s->width = head[3];
    s->height = head[4];
    s->vertices.resize(size_t(head[1]) * 3);
    s->indices.resize(size_t(head[2]) * 3);
    s->object.resize(size_t(head[2]));
    ok = std::fread(s->camera, 4, 15, f) == 15 && std::fread(s->light, 4, 12, f) == 12 &&
         std::fread(s->vertices.data(), 4, s->vertices.size(), f) == s->vertices.size() &&
         std::fread(s->indices.data(), 4, s->indices.size(), f) == s->indices.size() &&
         std::fread(s->object.data(), 4, s->object.size(), f) == s->object.size();
  }
  std::fclose(f);
  return ok;
}

RTCGeometry triangle_geometry(RTCDevice dev, const std::vector<float>& verts, const std::vector<uint32_t>& idx) {
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  float* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, verts.size() / 3));
  std::memcpy(v, verts.data(), verts.size() * 4);
  unsigned* i = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, idx.size() / 3));
  std::memcpy(i, idx.data(), idx.size() * 4);
  rtcCommitGeometry(g);
  return g;
}

struct Options {
  const char* scene = nullptr;
  uint64_t rays = 10000000;
  int threads = 2;
  int max_depth = 5;  // bounces after the primary hit (Lantern/Cycles default diffuse bounces: 4, +1)
  float rr = 0.7f;    // Russian-roulette survival probability from bounce 3
  bool shadow = true;
  bool two_level = false;
  uint64_t seed = 1;
};

struct Counts {
  uint64_t intersect = 0, occluded = 0, hits = 0;
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto val = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--rays")
      o.rays = std::strtoull(val(), nullptr, 10);
    else if (a == "--threads")
      o.threads = std::atoi(val());
    else if (a == "--max-depth")
      o.max_depth = std::atoi(val());
    else if (a == "--rr")
      o.rr = float(std::atof(val()));
    else if (a == "--mode") {
      std::string m = val();
      if (m == "path")
        o.shadow = true;
      else if (m == "closest")
        o.shadow = false;
      else {
        std::fprintf(stderr, "unknown mode %s (path, closest)\n", m.c_str());
        return 2;
      }
    } else if (a == "--two-level")
      o.two_level = true;
    else if (a == "--seed")
      o.seed = std::strtoull(val(), nullptr, 10);
    else if (a[0] != '-' && !o.scene)
      o.scene = argv[i];
    else {
      std::fprintf(stderr,
                   "usage: embree_raw SCENE.bin [--rays N] [--threads N] [--mode path|closest] "
                   "[--max-depth N] [--rr Q] [--two-level] [--seed S]\n");
      return 2;
    }
  }
  SceneFile sf;
  if (!o.scene || !read_scene(o.scene, &sf)) {
    std::fprintf(stderr, "embree_raw: cannot read scene file %s\n", o.scene ? o.scene : "(none)");
    return 1;
  }
  if (o.threads < 1) o.threads = int(std::thread::hardware_concurrency());

  auto t_build0 = std::chrono::steady_clock::now();
  RTCDevice dev = rtcNewDevice(nullptr);
  RTCScene top = rtcNewScene(dev);
  std::vector<RTCScene> subscenes;
  std::vector<uint32_t> all_idx(sf.indices.begin(), sf.indices.end());
  if (!o.two_level) {
    RTCGeometry g = triangle_geometry(dev, sf.vertices, all_idx);
    rtcAttachGeometry(top, g);
    rtcReleaseGeometry(g);
  } else {
    // One Embree scene per object, instanced with an identity transform: the same two-level
    // structure (and instance traversal cost) as Lantern's geometry.
    std::map<int, std::vector<uint32_t>> per_object;
    for (size_t t = 0; t < sf.object.size(); ++t)
      for (int c = 0; c < 3; ++c) per_object[sf.object[t]].push_back(all_idx[3 * t + c]);
    const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (auto& kv : per_object) {
      RTCScene sub = rtcNewScene(dev);
      RTCGeometry g = triangle_geometry(dev, sf.vertices, kv.second);
      rtcAttachGeometry(sub, g);
      rtcReleaseGeometry(g);
      rtcCommitScene(sub);
      subscenes.push_back(sub);
      RTCGeometry inst = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(inst, sub);
      rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, identity);
      rtcCommitGeometry(inst);
      rtcAttachGeometry(top, inst);
      rtcReleaseGeometry(inst);
    }
  }
  rtcCommitScene(top);
  double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build0).count();

  const V3 cam_o{sf.camera[0], sf.camera[1], sf.camera[2]};
  const V3 c00{sf.camera[3], sf.camera[4], sf.camera[5]}, c10{sf.camera[6], sf.camera[7], sf.camera[8]},
      c01{sf.camera[9], sf.camera[10], sf.camera[11]};
  const V3 du = (c10 - c00) * (1.0f / sf.width), dv = (c01 - c00) * (1.0f / sf.height);
  const V3 l0{sf.light[0], sf.light[1], sf.light[2]}, l1{sf.light[3], sf.light[4], sf.light[5]},
      l3{sf.light[9], sf.light[10], sf.light[11]};
  const V3 le1 = l1 - l0, le2 = l3 - l0;
  const uint64_t pixels = uint64_t(sf.width) * uint64_t(sf.height);

  constexpr uint64_t kChunk = 256;  // pixel samples per work item, in scanline order
  std::atomic<uint64_t> next_chunk{0}, traced{0};
  std::vector<Counts> counts(o.threads);

  auto worker = [&](int tid) {
    Counts c;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    while (traced.load(std::memory_order_relaxed) < o.rays) {
      uint64_t chunk = next_chunk.fetch_add(1);
      Rng rng(o.seed * 0x9E3779B97F4A7C15ULL + chunk);
      uint64_t before = c.intersect + c.occluded;
      for (uint64_t k = chunk * kChunk; k < (chunk + 1) * kChunk; ++k) {
        uint64_t pix = k % pixels;
        float px = float(pix % sf.width) + rng.uniform(), py = float(pix / sf.width) + rng.uniform();
        V3 org = cam_o, dir = normalize(c00 + du * px + dv * py - cam_o);
        for (int depth = 0;; ++depth) {
          RTCRayHit rh;
          rh.ray.org_x = org.x, rh.ray.org_y = org.y, rh.ray.org_z = org.z;
          rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
          rh.ray.tnear = 0.0f;
          rh.ray.tfar = INFINITY;
          rh.ray.mask = 0xffffffffu;
          rh.ray.flags = 0;
          rh.ray.time = 0;
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(top, &ctx, &rh);
          ++c.intersect;
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || depth >= o.max_depth) break;
          ++c.hits;
          V3 n = normalize(V3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
          if (dot(n, dir) > 0) n = n * -1.0f;
          V3 p = org + dir * rh.ray.tfar;
          p = p + n * (1e-4f * (1.0f + std::fmax(std::fabs(p.x), std::fmax(std::fabs(p.y), std::fabs(p.z)))));
          if (o.shadow) {
            V3 target = l0 + le1 * rng.uniform() + le2 * rng.uniform();
            V3 d = target - p;
            float dist = std::sqrt(dot(d, d));
            RTCRay sr;
            sr.org_x = p.x, sr.org_y = p.y, sr.org_z = p.z;
            sr.dir_x = d.x / dist, sr.dir_y = d.y / dist, sr.dir_z = d.z / dist;
            sr.tnear = 0.0f;
            sr.tfar = dist * (1 - 1e-4f);
            sr.mask = 0xffffffffu;
            sr.flags = 0;
            sr.time = 0;
            rtcOccluded1(top, &ctx, &sr);
            ++c.occluded;
          }
          if (depth >= 3 && rng.uniform() >= o.rr) break;
          // Cosine-distributed direction about n (Malley's method).
          float u1 = rng.uniform(), u2 = rng.uniform();
          float r = std::sqrt(u1), phi = 6.2831853f * u2;
          V3 t = std::fabs(n.x) > 0.9f ? V3{0, 1, 0} : V3{1, 0, 0};
          V3 b1 = normalize(cross(t, n)), b2 = cross(n, b1);
          dir = normalize(b1 * (r * std::cos(phi)) + b2 * (r * std::sin(phi)) + n * std::sqrt(std::fmax(0.0f, 1 - u1)));
          org = p;
        }
      }
      traced.fetch_add(c.intersect + c.occluded - before, std::memory_order_relaxed);
    }
    counts[tid] = c;
  };

  // CPU time of the process as well as wall time: on a busy machine the rate per CPU second is
  // the figure that other processes disturb least.
  auto cpu_now = [] {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  };
  const double cpu0 = cpu_now();
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  for (int t = 0; t < o.threads; ++t) pool.emplace_back(worker, t);
  for (auto& th : pool) th.join();
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu_secs = cpu_now() - cpu0;

  Counts total;
  for (const Counts& c : counts) {
    total.intersect += c.intersect;
    total.occluded += c.occluded;
    total.hits += c.hits;
  }
  uint64_t rays = total.intersect + total.occluded;
  std::printf(
      "{\"rays\": %llu, \"intersect_rays\": %llu, \"occluded_rays\": %llu, \"seconds\": %.6f, "
      "\"rays_per_second\": %.1f, \"cpu_seconds\": %.6f, \"rays_per_cpu_second\": %.1f, \"intersect_rays_per_second\": "
      "%.1f, \"threads\": %d, "
      "\"mode\": \"%s\", \"two_level\": %s, \"max_depth\": %d, \"rr\": %.3f, \"triangles\": %zu, "
      "\"build_seconds\": %.6f, \"pixel_samples\": %llu}\n",
      (unsigned long long)rays, (unsigned long long)total.intersect, (unsigned long long)total.occluded, secs,
      rays / secs, cpu_secs, rays / cpu_secs, total.intersect / secs, o.threads, o.shadow ? "path" : "closest",
      o.two_level ? "true" : "false", o.max_depth, o.rr, sf.object.size(), build_s,
      (unsigned long long)(next_chunk.load() * kChunk));
  for (RTCScene s : subscenes) rtcReleaseScene(s);
  rtcReleaseScene(top);
  rtcReleaseDevice(dev);
  return 0;
}
