// The film: per-pixel accumulators (float sums, as Cycles' render buffers) of the passes a render
// asks for, the pixel filter, and a published Combined image that readers see while it renders.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <utility>
#include <vector>

#include "core/cryptomatte.h"
#include "core/fresh_pages.h"
#include "core/math.h"

namespace lt {

enum class FilterType { Box = 0, Gaussian = 1, BlackmanHarris = 2 };

// Importance-samples the pixel filter, as Cycles does (film.cpp: filter_table): each sample lands
// in exactly one pixel with weight 1, at an offset drawn from the filter's 1D profile, separably
// in x and y. Blackman-Harris spans [-w, w], Gaussian [-1.5w, 1.5w] (sigma w/4), Box [-w/2, w/2].
class FilterSampler {
 public:
  FilterSampler(FilterType type, float width);
  float sample(float u) const;    // offset from the pixel centre, in pixels
  float pdf(float offset) const;  // density of sample() at an offset (normalised: integrates to 1)
  float radius() const { return half_range_; }

 private:
  // The profile over [0, radius] as a piecewise-constant distribution in float, inverted through
  // a guide table: two lookups per camera sample, on the hot path.
  std::vector<float> cdf_, inv_width_, density_;
  std::vector<uint32_t> guide_;
  float half_range_ = 0.5f;
};

// Cycles' light passes (kernel/film/light_passes.h), in lt_pass order from DiffuseDirect: what a
// sample's radiance holds split by its path's first bounce (direct: the light reached from the
// first scattering vertex; indirect: the rest; Emission and Environment: seen directly), and the
// first hit's closure colours per kind. kLightSums: the light parts, which sum to the radiance.
enum LightPart {
  kDiffuseDirect,
  kDiffuseIndirect,
  kDiffuseColor,
  kGlossyDirect,
  kGlossyIndirect,
  kGlossyColor,
  kTransmissionDirect,
  kTransmissionIndirect,
  kTransmissionColor,
  kVolumeDirect,
  kVolumeIndirect,
  kEmission,
  kEnvironment,
  kLightParts
};

// A contribution several light groups share (the volume emission of overlapping media): share[i]
// of it, per channel, goes to group[i] (-1: none); the shares sum to 1.
struct LightgroupShares {
  static constexpr int kMax = 8;  // VolumeStack::kCapacity
  int n = 0;
  int group[kMax];
  Spectrum share[kMax];
};

// The largest magnitude a sample's value may have: the film's float sums over samples (and their
// squares, for Variance) hold about 1e8 samples of it. No light of a real scene comes near (a 1 MW
// point light 10 um away gives about 1e14); a sample beyond it is dropped as a NaN one is.
constexpr float kMaxSampleValue = 1e15f;
inline bool in_range(float v) { return std::abs(v) <= kMaxSampleValue; }                       // false for NaN
inline bool in_range(const Vec3& v) { return in_range(v.x) & in_range(v.y) & in_range(v.z); }  // no branches

struct SampleValue {
  Spectrum radiance{0.0f};
  float alpha = 0;
  float depth = 1e10f;  // Blender's background depth
  Vec3 normal{0.0f};
  Spectrum albedo{0.0f};
  // Denoising features, as Cycles writes them (film/denoising_passes.h): the first hit's normal in
  // camera space (x right, y up, z forward) and its distance along the camera ray (0: none). Set
  // by the render job from normal and depth when the film keeps them.
  Vec3 feature_normal{0.0f};
  float feature_distance = 0;
  // Light passes (LightPart), written when IntegratorSettings::light_passes is set.
  Spectrum light[kLightParts];
  // Data passes of the camera ray's first hit, as Cycles' film_write_data_passes: world position,
  // UV (u, v, 1 as Cycles' primitive_uv; 0 on the background), the Mist pass's coverage
  // (1 - mist), object and material pass_index.
  Vec3 position{0.0f}, uv{0.0f};
  float mist = 0, object_index = 0, material_index = 0;
  // Cryptomatte (CryptomatteType order): the first hit's object, material and asset ids
  // (cryptomatte_id; 0: none) and its weight, the throughput's average there (Cycles' matte_weight
  // without the transparency factor: Lantern chooses to pass a transparent layer or not).
  float crypto_id[kCryptoTypes] = {0, 0, 0};
  float crypto_weight = 0;
  // Cycles' AO pass (throughput x the AO ray's transmittance) and Vector pass (the film motion
  // to the previous and from the next frame; vector_weight 1 where the sample wrote one: the pass
  // is the mean over those samples, as Cycles' pass_motion_weight).
  Spectrum ao{0.0f};
  float vector[4] = {0, 0, 0, 0};
  float vector_weight = 0;
  // Light groups (Cycles' Combined_<group>): the radiance per group of the emitter each
  // contribution comes from, into a buffer of FilmLayout::lightgroups the render job zeroes
  // (CameraSample::lightgroups); null when the film keeps none.
  Spectrum* lightgroups = nullptr;
  void add_lightgroup(int group, const Spectrum& c) {
    if (lightgroups && group >= 0) lightgroups[group] += c;
  }
  void add_lightgroup(const LightgroupShares& g, const Spectrum& c) {
    for (int i = 0; lightgroups && i < g.n; ++i) add_lightgroup(g.group[i], c * g.share[i]);
  }
  // Shader AOVs: 4 floats per AOV of FilmLayout::aovs (ShadingContext::aovs), zeroed by the render
  // job (CameraSample::aovs); null when the film keeps none.
  float* aovs = nullptr;
  // Shadow catcher (Cycles' catcher split, integrators/path.cpp), when FilmLayout::shadow_catcher:
  // the light of the catcher-only path (PASS_SHADOW_CATCHER), the light and transparency of the
  // camera path before it met a catcher (PASS_SHADOW_CATCHER_MATTE; the throughput there counts as
  // transparency), 1 when it met one (PASS_SHADOW_CATCHER_SAMPLE_COUNT), and the world the camera
  // ray sees directly or behind the catcher (PASS_BACKGROUND, for the approximate Combined).
  Spectrum catcher{0.0f}, matte{0.0f}, background{0.0f};
  float matte_transparent = 0, catcher_split = 0;
};

// NoisyImage: Combined before denoising (equal to Combined when the render is not denoised).
// Denoising*: Cycles' denoising data passes, the means of SampleValue's albedo and features.
enum class Pass {
  Combined = 0,
  Depth = 1,
  Normal = 2,
  Albedo = 3,
  Variance = 4,
  SampleCount = 5,
  NoisyImage = 6,
  DenoisingNormal = 7,
  DenoisingAlbedo = 8,
  DenoisingDepth = 9,
  // Cycles' light passes (LightPart order) and data passes.
  DiffuseDirect = 10,
  DiffuseIndirect = 11,
  DiffuseColor = 12,
  GlossyDirect = 13,
  GlossyIndirect = 14,
  GlossyColor = 15,
  TransmissionDirect = 16,
  TransmissionIndirect = 17,
  TransmissionColor = 18,
  VolumeDirect = 19,
  VolumeIndirect = 20,
  Emission = 21,
  Environment = 22,
  Position = 23,
  UV = 24,
  Mist = 25,
  ObjectIndex = 26,
  MaterialIndex = 27,
  AO = 28,
  Vector = 29,
  // Cycles' Shadow Catcher pass, read from the film's catcher accumulators (not a sum of its own).
  ShadowCatcher = 30,
  Count = 31
};
constexpr int kFirstSummedPass = int(Pass::DiffuseDirect);
constexpr int kSummedPasses = int(Pass::Count) - kFirstSummedPass;
inline bool is_light_pass(Pass p) { return p >= Pass::DiffuseDirect && p <= Pass::Environment; }
// The Colour pass a Direct or Indirect pass is divided by when read (Cycles' divide_type); Count: none.
Pass light_pass_color(Pass p);
// a / b per RGB channel as Cycles' safe_divide_even_color (util/math.h): a channel whose divisor
// is zero takes the other channels' ratio.
void divide_even_color(const double* a, const double* b, float* o);
// The pass's channel names in Lantern's EXR files ("DiffDir.R", ...), Blender's pass name and
// channel letters; nullptr for the passes the files do not hold.
const char* exr_pass_name(Pass p);
const char* exr_channel_letters(Pass p);
int pass_channels(Pass pass);
constexpr unsigned pass_bit(Pass p) { return 1u << unsigned(p); }
constexpr unsigned kAllPasses = (1u << unsigned(Pass::Count)) - 1;
// What a render keeps unless asked otherwise: every pass but AO (its rays cost time) and Vector
// (it needs the neighbouring frames' motion).
constexpr unsigned kDefaultPasses = kAllPasses & ~(pass_bit(Pass::AO) | pass_bit(Pass::Vector));
constexpr unsigned kDenoisingFeatures =
    pass_bit(Pass::DenoisingNormal) | pass_bit(Pass::DenoisingAlbedo) | pass_bit(Pass::DenoisingDepth);
// Per pixel, the features a denoiser reads: camera-space normal (3), albedo (3), distance (1).
constexpr int kFeatureChannels = 7;

// Shadow catchers: a pixel's means over its samples of what Cycles' catcher passes hold (SampleValue
// ::catcher ...), and Combined's (RGB and alpha), from which Combined and the Shadow Catcher pass are
// read (the film, and io/merge.cpp for merged parts).
struct CatcherPixel {
  double combined[3] = {0, 0, 0}, alpha = 0;
  double catcher[3] = {0, 0, 0}, matte[4] = {0, 0, 0, 0}, split = 0, background[3] = {0, 0, 0};
  // BDPT's light-tracing splats (over the light paths): light of paths that met no catcher, so
  // the matte's and Combined's alike (bdpt.cpp splats none onto a catcher the camera sees).
  double splat[3] = {0, 0, 0};
};
// Cycles' film_calculate_shadow_catcher (film/read.h): 1 where no sample split.
void catcher_pass(const CatcherPixel& m, double* rgb);
// Cycles' Combined with catchers: the matte pass (Film::get_actual_display_pass), `approximate`: with
// the shadow composited in (film_calculate_shadow_catcher_matte_with_shadow), over the world behind
// unless `transparent`.
void catcher_combined(const CatcherPixel& m, bool approximate, bool transparent, float* rgba);
// The EXR channels of the catcher means (CatcherPixel order, "CatcherCombined.R" ...): parts keep
// them so that merges recompute Combined and the Shadow Catcher pass exactly.
enum CatcherPart { kCatcherCombined, kCatcherLight, kCatcherMatte, kCatcherSplit, kCatcherBackground, kCatcherParts };
const char* catcher_part_name(int part);
const char* catcher_part_letters(int part);

// A film's two half images (see ErrorEstimate) of Combined and of the denoising features, the
// means of each half per pixel: what a denoiser reads (denoise/). Pixels without a sample in
// both halves are not valid (their values are zero).
struct HalfImages {
  int width = 0, height = 0;
  FreshVector<float> color[2];  // RGB: half A (odd-numbered samples: 1st, 3rd, ...), half B
  // RGB: variance of each half's mean from that half's samples alone (Film::half_images), so that a
  // denoiser guided by one half weighs the other with weights independent of it.
  FreshVector<float> variance[2];
  FreshVector<float> feature[2];  // kFeatureChannels per pixel
  FreshVector<uint8_t> valid;
};

// What a film keeps: the passes (Combined and Sample Count always), and whether it keeps the sum
// of squares (the Variance pass, adaptive sampling), splats (BDPT) and a strategy grid.
struct FilmLayout {
  unsigned passes = kAllPasses;
  bool squares = true;
  bool splats = false;
  int strategy_cells = 0;
  // Cryptomatte: the types kept (bit 1 << CryptomatteType) and Blender's Levels; each type keeps
  // 2 x cryptomatte_layers(levels) (id, weight) slots per pixel.
  unsigned cryptomatte = 0;
  int cryptomatte_levels = 6;
  int cryptomatte_slots() const { return cryptomatte ? 2 * cryptomatte_layers(cryptomatte_levels) : 0; }
  int lightgroups = 0;  // light group passes (Combined_<group>), RGB each
  int aovs = 0;         // shader AOV passes, 4 floats each
  // Shadow catchers (SampleValue::catcher ...): kept when the scene has one and the integrator
  // splits paths there; Combined then reads as Cycles' matte, approximated (the catchers' shadows
  // composited in, over the world behind them unless `transparent`) or not.
  bool shadow_catcher = false, catcher_approximate = true, transparent = false;
  // Bytes per pixel of the accumulators and the published image.
  size_t bytes_per_pixel() const;
};

// The image's relative error, estimated from two independent half images A (a pixel's even-
// numbered samples, its 1st, 3rd, ...) and B (its odd-numbered ones) of the Combined RGB:
//   v_p = sum_c (A_pc - B_pc)^2 n_A n_B / n^2      unbiased for Var[I_pc] summed over channels
//   E^2 = sum_p v_p / (sum_pc I_pc^2 - sum_p v_p)   (the denominator unbiased for sum_pc R_pc^2)
// i.e. E estimates sqrt(E[sum (I - R)^2] / sum R^2), the RMS error relative to the RMS of the
// converged image R. Since E[(A - B)^2] = Var A + Var B for independent halves, v_p needs no model
// of the noise; BDPT splats are split into halves the same way (by the sample that traced the
// light path) and normalised by each half's light paths.
// Pixels holding fewer than 2 finite samples once 2 or more passes are done (every sample there was
// discarded as not finite, e.g. under an emitter of strength 1e38) cannot be estimated: they are
// left out of both sums and counted, so that they neither block the estimate nor the noise target.
struct ErrorEstimate {
  double rel_error = -1;            // E; negative before 2 passes; +inf if noise >= signal
  double mean_square = 0;           // sum_pc R_pc^2 / pixels (estimated): the adaptive sampler's scale
  double variance = 0;              // sum_p v_p
  uint64_t unestimated_pixels = 0;  // pixels with fewer than 2 finite samples, left out
};

class Film {
 public:
  // Allocates everything a render writes (publishing and reading allocate nothing more).
  Film(int width, int height, const FilmLayout& layout = FilmLayout());
  int width() const { return width_; }
  int height() const { return height_; }
  bool has(Pass pass) const { return (layout_.passes & pass_bit(pass)) != 0; }
  // Whether every value of s this film keeps lies within kMaxSampleValue (so is neither NaN nor
  // infinite): the render job drops and counts a sample that does not, so that an extreme
  // material (a colour of 1e38) cannot put an infinity into any pass. Only the kept passes are
  // read: the check costs a few nanoseconds a sample when the film keeps Combined alone.
  bool accepts(const SampleValue& s) const;
  bool has_features() const { return !feature_.empty(); }
  const FilmLayout& layout() const { return layout_; }
  // Only the thread that owns the pixel in the current pass writes it.
  void add(int x, int y, const SampleValue& s);
  // The half (0: A, 1: B) the pixel's next sample goes to.
  int next_half(int x, int y) const { return int(count_[size_t(y) * width_ + x] & 1u); }
  // Light-tracing contributions (BDPT's t = 1): summed per pixel and divided, when read, by the
  // number of light paths traced for the whole region (each one may reach any pixel). `half`:
  // that of the camera sample whose light path made the splat. Needs FilmLayout::splats.
  void add_splat(uint32_t pixel, const Spectrum& v, int half) {
    for (int k = 0; k < 3; ++k) splat_[3 * size_t(pixel) + k] += v[k];
    if (half)
      for (int k = 0; k < 3; ++k) splat_half_[3 * size_t(pixel) + k] += v[k];
    if (splat_sq_.empty()) return;
    for (int k = 0; k < 3; ++k) splat_sq_[(2 * size_t(pixel) + half) * 3 + k] += v[k] * v[k];
  }
  // A splat's part of a light pass (LightPart; not a Colour), when the film keeps it.
  void add_light_splat(uint32_t pixel, int part, const Spectrum& v) {
    std::vector<float>& a = light_splat_[part];
    if (a.empty()) return;
    for (int k = 0; k < 3; ++k) a[3 * size_t(pixel) + k] += v[k];
  }
  bool has_light_passes() const;
  // Light groups: a splat's part (BDPT), and the group's pass, RGB per pixel as read_rows (the
  // mean over samples plus the splats over the light paths); light_tracing: the splats' part alone
  // (false without splats).
  int lightgroups() const { return layout_.lightgroups; }
  void add_lightgroup_splat(uint32_t pixel, int group, const Spectrum& v) {
    if (lightgroup_splat_.empty() || group < 0) return;
    for (int k = 0; k < 3; ++k) lightgroup_splat_[(size_t(pixel) * layout_.lightgroups + group) * 3 + k] += v[k];
  }
  void read_lightgroup_rows(int group, int y0, int rows, float* out) const;
  // Shader AOV `index`: the mean over samples of its first `channels` floats (1: a value, 4: a
  // colour and its coverage), rows as read_rows.
  int aovs() const { return layout_.aovs; }
  void read_aov_rows(int index, int channels, int y0, int rows, float* out) const;
  bool read_lightgroup_light_tracing(int group, float* out) const;
  // Light paths behind the published splats (0 without splats): what a merge weights them by.
  uint64_t published_light_paths() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return published_light_paths_;
  }
  void add_light_paths(uint64_t n, uint64_t n_half) {
    light_paths_ += n;
    light_paths_half_ += n_half;
  }
  // Of the accumulators (the rendering thread, between passes) after `passes` passes over every
  // pixel (fewer than 2: no estimate); see ErrorEstimate.
  ErrorEstimate error_estimate(int passes) const;
  // Variance of the pixel's Combined RGB mean (summed over channels) from its camera samples'
  // sample variance; 0 below 2 samples. Needs FilmLayout::squares.
  double pixel_variance(int x, int y) const;
  uint32_t count(int x, int y) const { return count_[size_t(y) * width_ + x]; }
  // BDPT's strategy view: per pixel, one RGB accumulator per strategy cell. Camera-side
  // contributions are averaged over the pixel's samples, splats over the light paths.
  int strategy_cells() const { return layout_.strategy_cells; }
  void add_strategies(int x, int y, const Spectrum* values) {
    const int cells = layout_.strategy_cells;
    float* o = &strategies_[(size_t(y) * width_ + x) * cells * 3];
    for (int c = 0; c < cells; ++c)
      for (int k = 0; k < 3; ++k) o[3 * c + k] += values[c][k];
  }
  void add_strategy_splat(uint32_t pixel, int cell, const Spectrum& v) {
    float* o = &strategy_splats_[(size_t(pixel) * layout_.strategy_cells + cell) * 3];
    for (int k = 0; k < 3; ++k) o[k] += v[k];
  }
  // The grid of strategy images: `columns` x `rows` cells of the region's size, RGB, rows bottom
  // to top with depth 0 at the top. Only valid once rendering has stopped.
  // y0, count: only grid rows [y0, y0 + count) (count < 0: to the last), written from out on.
  void read_strategy_grid(int columns, int rows, float* out, int y0 = 0, int count = -1) const;
  // Resolves Combined into the published image readers see while rendering (the rendering
  // thread, between passes). Allocates nothing. `denoised`: the film's denoised RGB (as
  // set_denoised's) to publish in place of Combined's (its alpha stays the film's).
  void publish(const std::vector<float>* denoised = nullptr);
  // Whether the published image is denoised, and the published image itself, RGBA (tests: once
  // rendering has stopped, read() gives the accumulators).
  bool published_denoised() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return published_denoised_;
  }
  void read_published(float* out) const;
  // The rendering thread writes the accumulators between these (one pass); readers of anything
  // but Combined wait for the end of the pass, and the next pass waits for readers waiting.
  void begin_writing();
  void end_writing();
  // Rendering has stopped: from now on readers read the accumulators themselves (every pass).
  void finish();
  // Labels drawn over Combined when it is read (never accumulated): per pixel a LabelPixel of
  // core/label_font.h, rows bottom to top; empty for none. Set before rendering starts.
  void set_labels(std::vector<uint8_t> mask) { labels_ = std::move(mask); }
  // Resolves a pass: width*height*channels floats, rows bottom to top. While rendering, Combined
  // is the published image (zeros before the first publish) and the other passes are read between
  // two passes (waiting for the one being rendered); only the passes the film keeps (StateError).
  // `labels` false: Combined without the labels (tests).
  void read(Pass pass, float* out, bool labels = true) const { read_rows(pass, 0, height_, out, labels); }
  // The same for rows [y0, y0 + rows) only (rows bottom to top): width*rows*channels floats, so
  // that a reader copies a frame through a band-sized buffer.
  void read_rows(Pass pass, int y0, int rows, float* out, bool labels = true) const;
  // A Cryptomatte layer (CryptoObject00, 01, ...) of rows [y0, y0 + rows): per pixel id, coverage,
  // id, coverage (the pixel's slots 2 layer and 2 layer + 1 once sorted by weight, largest first;
  // coverage: the weight's mean over the pixel's samples), as Cycles' passes. Between passes, as
  // read(); StateError for a type the film does not keep.
  void read_cryptomatte_rows(int type, int layer, int y0, int rows, float* out) const;
  bool has_cryptomatte(int type) const { return (layout_.cryptomatte >> type) & 1u; }
  // The light-tracing (t = 1 splat) part of Combined, RGB per pixel; false when the render traced
  // no light paths (not bidirectional). Between passes, as read().
  bool read_light_tracing(float* out) const;
  // The same for a light pass (not a Colour): its splats' part, undivided (merges need it apart).
  bool read_light_tracing(Pass pass, float* out) const;
  // The Vector pass's coverage, per pixel the share of its samples that wrote a vector (what a
  // merge weights the parts' vectors by); false when the film does not keep the pass.
  bool read_vector_coverage(float* out) const;
  // A catcher part's means (CatcherPart; channels as catcher_part_letters) for every pixel; false
  // when the film keeps no catcher sums. Between passes, as read().
  bool read_catcher_part(int part, float* out) const;
  uint64_t total_samples() const;
  // The half images (the rendering thread, once the last pass is done); needs the features.
  HalfImages half_images() const;
  // The denoised Combined RGB (width*height*3, rows bottom to top; its alpha stays the film's):
  // once set, reading Combined gives it and NoisyImage the film's own. Before finish().
  void set_denoised(std::vector<float> rgb);
  bool denoised() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !denoised_.empty();
  }

 private:
  void resolve_combined(size_t i, float* o) const;
  CatcherPixel catcher_pixel(size_t i) const;
  void read_summed(Pass pass, size_t i, float* o) const;  // a pass from DiffuseDirect on, pixel i
  // Pixel i's means of Combined RGB over half A, half B and all its samples (count >= 2), light
  // tracing's splats split the same way and normalised by each half's light paths.
  struct SplatScales {
    bool on = false;
    double inv_la = 0, inv_lb = 0, inv_l = 0;
  };
  SplatScales splat_scales() const;
  void half_means(size_t i, const SplatScales& sc, double* a, double* b, double* mean) const;
  // Pixel i's variance of each half's mean (var[half][channel]), from that half's samples and
  // splats alone where it holds 2 or more samples; a, b: its half means. Needs the features.
  void half_variances(size_t i, const SplatScales& sc, const double* a, const double* b, double (*var)[3]) const;
  // Locks the film for reading the accumulators: waits while a pass is being rendered.
  std::unique_lock<std::mutex> lock_accumulators() const;
  int width_, height_;
  FilmLayout layout_;
  // Structure of arrays, so that a pass nobody asked for costs nothing.
  // mean_: the running mean of Combined RGB; m2_: the sum of squared deviations from it (Welford);
  // half_: the running mean of the pixel's odd-numbered samples (its 2nd, 4th, ...), which with
  // the rest make two independent half images for the error estimate (Film::error_estimate).
  // alpha_, normal_, albedo_: sums; depth_: the minimum.
  std::vector<float> mean_, m2_, half_, alpha_, normal_, albedo_, depth_;
  // The denoising features (kFeatureChannels per pixel): sums over all samples and over the
  // odd-numbered ones; empty unless a Denoising pass is kept. denoised_: set_denoised's RGB.
  std::vector<float> feature_, feature_half_, denoised_;
  std::vector<uint32_t> count_;
  std::vector<float> splat_, splat_half_;  // empty without splats
  // For the half images' variances (kept with the denoising features): m2_half_, half_'s sum of
  // squared deviations (Welford; half A's follows from m2_); splat_sq_, each half's sum of squared
  // splats (half A's RGB, then half B's, per pixel; with splats).
  std::vector<float> m2_half_, splat_sq_;
  // The light and data passes (Pass::DiffuseDirect on): per pass a sum over samples (Position and
  // the indices: the pixel's first sample's value, as Cycles writes them at sample 0), empty when
  // not kept; light_splat_: the light passes' part of the splats (BDPT).
  std::vector<float> sums_[kSummedPasses];
  std::vector<int> summed_kept_;  // the indices of sums_ kept (add() visits only those)
  std::vector<float> light_splat_[kLightParts];
  // Cryptomatte: per kept type, FilmLayout::cryptomatte_slots() (id, weight sum) pairs per pixel.
  std::vector<float> crypto_[kCryptoTypes];
  std::vector<float> lightgroup_, lightgroup_splat_;  // per pixel, per group, RGB sums
  std::vector<float> aov_;                            // per pixel, per AOV, 4 sums
  // Shadow catcher sums (FilmLayout::shadow_catcher): catcher-only light (RGB), matte (RGB and
  // transparency), splits, world behind (RGB).
  std::vector<float> catcher_, matte_, splits_, background_;
  uint64_t light_paths_ = 0, light_paths_half_ = 0, published_light_paths_ = 0;
  std::vector<float> strategies_, strategy_splats_;
  std::vector<uint8_t> labels_;
  std::vector<uint16_t> published_;  // Combined RGBA, half floats
  bool published_valid_ = false, published_denoised_ = false, finished_ = false, writing_ = false;
  mutable int readers_waiting_ = 0;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
};

}  // namespace lt
