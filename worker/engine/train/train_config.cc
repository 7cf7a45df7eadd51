#include "worker/engine/train/train_config.h"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "common/error.h"
#include "worker/engine/train/config_check.h"

namespace endorecon::train {

TrainConfig TrainConfig::Preset(const std::string& name) {
  TrainConfig c;
  c.preset = name;
  // Measured on the demo clip (3000 iterations, held-out tissue PSNR): these rates 34.5 dB against
  // 32.3 dB with grid 1e-2 and heads 1e-3 (docs/benchmarks.md). The density head at 6e-3 rather
  // than 3e-3: +0.55 dB held out on the real-texture clip at 120 s, +0.05-0.1 dB on the demo clip,
  // at about 0.015 of the demo's uncertainty ranking ("Against the truth", docs/benchmarks.md).
  // The learned background starts fitted to the frames' borders (train/background_start.h) and moves
  // at the heads' rate: 3e-2 let it chase the field's residuals (docs/benchmarks.md).
  c.adam.lr = {{"grid", 3e-2f},    {"blend", 1e-3f}, {"deform", 1e-3f},
               {"density", 6e-3f}, {"color", 3e-3f}, {"background", 3e-3f}};
  if (name == "cpu") {
    c.field = field::FieldConfig::Cpu();
    c.nll_weight = 0.0075f;  // train_config.h
    // The deformation at 3e-4, not 1e-3: Adam moves every vertex by about its rate a step, and at
    // 1e-3 those the photometric loss barely constrains wandered (1.4-1.6 px off the real-texture
    // clip's true motion after 120 s, 0.9 px at 3e-4, 0.8 px at the flow start). At 120 s: +0.1 dB
    // held out and +0.5 dB on the training frames there, +0.3 dB held out on the demo clip (+0.9 dB
    // against the truth), +0.25 dB from a zero start; at 300 s the demo's model map ranks its smaller
    // error less well (docs/benchmarks.md, "The deformation's rate").
    c.adam.lr["deform"] = 3e-4f;
    c.depth_refine_every = 0.25;
    c.depth_refine_samples = 16;
    c.depth_refine_pixels = 100000;
    return c;
  }
  if (name == "paper") {
    // The paper's grids and EndoNeRF's schedule: 50k iterations, 2048 rays, 64 + 32 samples.
    c.field = field::FieldConfig::Paper();
    c.iterations = 50000;
    c.rays_per_batch = 2048;
    c.depth_samples = 64;
    c.stratified_samples = 32;
    c.eval_coarse_samples = 64;
    c.eval_fine_samples = 64;
    c.curve_interval_s = 60;
    c.deformation_start = "zero";  // the paper's deformation learns from the loss alone
    return c;
  }
  if (name == "gpu") {
    // The cpu preset's settings, batch included: on an H200 no larger batch trained better in 20-30 s
    // (gpu_train_bench, docs/benchmarks.md "The gpu preset's batch, chosen on a GPU"): 2,048, 4,096
    // and 12,288 rays a step gave 0.3-0.8 dB less on the demo clip and 0.04 dB more to 0.16 dB less on
    // a 640 x 512, 160-frame clip than 1,024, though 1.4-1.9x the samples per second. It keeps its
    // name so jobs that ask for it keep working, and is where choices measured better on a GPU go.
    c = Preset("cpu");
    c.preset = name;
    return c;
  }
  FailInvalid("unknown preset '" + name + "' (expected cpu, gpu or paper)");
}

namespace {

// One table drives both directions so a key cannot be written and not read, or the reverse.
template <typename Visit>
void VisitKeys(TrainConfig& c, Visit&& visit) {
  visit("preset", c.preset);
  visit("iterations", c.iterations);
  visit("rays_per_batch", c.rays_per_batch);
  visit("depth_samples", c.depth_samples);
  visit("stratified_samples", c.stratified_samples);
  visit("depth_xi", c.depth_xi);
  visit("holdout", c.holdout);
  visit("nll_weight", c.nll_weight);
  visit("nll_beta", c.nll_beta);
  visit("rgb_l2_weight", c.rgb_l2_weight);
  visit("depth_weight", c.depth_weight);
  visit("variance_reg", c.variance_reg);
  visit("depth_loss", c.depth_loss);
  visit("huber_delta", c.huber_delta);
  visit("variance_eps", c.variance_eps);
  visit("adam.lr", c.adam.lr);
  visit("adam.default_lr", c.adam.default_lr);
  visit("adam.beta1", c.adam.beta1);
  visit("adam.beta2", c.adam.beta2);
  visit("adam.eps", c.adam.eps);
  visit("adam.final_lr_factor", c.adam.final_lr_factor);
  visit("adam.clip_norm", c.adam.clip_norm);
  visit("eval_coarse_samples", c.eval_coarse_samples);
  visit("eval_fine_samples", c.eval_fine_samples);
  visit("eval_floor", c.eval_floor);
  visit("mc_passes", c.mc_passes);
  visit("uncertainty_lambda", c.uncertainty_lambda);
  visit("adaptive_sampling", c.adaptive_sampling);
  visit("adaptive_warmup", c.adaptive_warmup);
  visit("adaptive_ray_fraction", c.adaptive_ray_fraction);
  visit("adaptive_refresh", c.adaptive_refresh);
  visit("adaptive_map_stride", c.adaptive_map_stride);
  visit("adaptive_floor", c.adaptive_floor);
  visit("depth_refine_every", c.depth_refine_every);
  visit("depth_refine_fraction", c.depth_refine_fraction);
  visit("depth_refine_ema", c.depth_refine_ema);
  visit("depth_refine_samples", c.depth_refine_samples);
  visit("depth_refine_pixels", c.depth_refine_pixels);
  visit("depth_fill_sigma", c.depth_fill_sigma);
  visit("occupancy_resolution", c.occupancy_resolution);
  visit("occupancy_every", c.occupancy_every);
  visit("occupancy_min_alpha", c.occupancy_min_alpha);
  visit("background", c.background);
  visit("outside_view", c.outside_view);
  visit("outside_view_level", c.outside_view_level);
  visit("exposure", c.exposure);
  visit("exposure_threshold", c.exposure_threshold);
  visit("still_threshold_px", c.still_threshold_px);
  visit("fit_depth_bounds", c.fit_depth_bounds);
  visit("deformation_start", c.deformation_start);
  visit("curve_interval_s", c.curve_interval_s);
  visit("curve_frames", c.curve_frames);
  visit("field.encoding", c.field.encoding);
  visit("field.frequencies", c.field.frequencies);
  visit("field.grids.base_resolutions", c.field.grids.base_resolutions);
  visit("field.grids.scales", c.field.grids.scales);
  visit("field.grids.levels", c.field.grids.levels);
  visit("field.grids.features", c.field.grids.features);
  visit("field.grids.log2_table", c.field.grids.log2_table);
  visit("field.grids.max_resolution", c.field.grids.max_resolution);
  visit("field.blend_hidden", c.field.blend_hidden);
  visit("field.deformation.enabled", c.field.deformation.enabled);
  visit("field.deformation.resolution", c.field.deformation.resolution);
  visit("field.deformation.time_knots", c.field.deformation.time_knots);
  visit("field.heads.density_hidden", c.field.heads.density_hidden);
  visit("field.heads.color_hidden", c.field.heads.color_hidden);
  visit("field.heads.geo_features", c.field.heads.geo_features);
  visit("field.heads.dropout", c.field.heads.dropout);
  visit("field.heads.color_dropout", c.field.heads.color_dropout);
  visit("field.heads.color_time_frequencies", c.field.heads.color_time_frequencies);
  visit("field.exposure_times", c.field.exposure_times);
  visit("field.learned_background", c.field.learned_background);
  visit("field.trained_times", c.field.trained_times);
}

nlohmann::json::json_pointer Pointer(const std::string& dotted) {
  std::string path = "/" + dotted;
  for (auto& ch : path) {
    if (ch == '.') ch = '/';
  }
  return nlohmann::json::json_pointer(path);
}

// nlohmann converts a JSON number to a narrower type with a plain cast, which is undefined when the
// value does not fit (tests/fuzz/train_config_fuzz.cc found 4.8e39 read into an int): every number
// is checked against its key's type first. Values of another JSON type are left to get_to, which
// refuses them.
template <typename T>
void RequireFits(const nlohmann::json& node, const char* key) {
  if constexpr (requires { typename T::mapped_type; }) {
    if (node.is_object()) {
      for (const auto& item : node) RequireFits<typename T::mapped_type>(item, key);
    }
  } else if constexpr (requires { typename T::value_type; }) {
    if (node.is_array()) {
      for (const auto& item : node) RequireFits<typename T::value_type>(item, key);
    }
  } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, double>) {
    if (!node.is_number()) return;
    const double v = node.get<double>();
    const double bound = std::is_integral_v<T> ? std::ldexp(1.0, std::numeric_limits<T>::digits)
                                               : double(std::numeric_limits<T>::max());
    const double low = std::is_signed_v<T> ? -bound : 0.0;
    const bool fits =
        std::is_integral_v<T> ? v == std::floor(v) && v >= low && v < bound : std::abs(v) <= bound;
    if (!fits) {
      FailInvalid(std::string("config: bad value for ") + key + ": " + node.dump() +
                  (std::is_integral_v<T> ? " is not a whole number in range" : " is out of a float's range"));
    }
  }
}

void Validate(const TrainConfig& c) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) FailInvalid("config: " + what);
  };
  require(c.iterations >= 0, "iterations must be >= 0");
  // Upper bounds where a value sizes memory (a batch of 1e9 rays took 7 GB and more before its first
  // step) or makes training meaningless (a negative rate or weight, a rate that diverges at once).
  require(c.rays_per_batch >= 1 && c.rays_per_batch <= kMostRaysPerBatch,
          "rays_per_batch must be in [1, " + std::to_string(kMostRaysPerBatch) + "], got " +
              std::to_string(c.rays_per_batch));
  // Each count of samples a ray is named when refused (the file's key is what a user fixes).
  const auto require_samples = [&](int value, int least, const char* key) {
    require(value >= least && value <= kMostSamplesPerRay,
            fmt::format("{} must be in [{}, {}], got {}", key, least, kMostSamplesPerRay, value));
  };
  require_samples(c.stratified_samples, 1, "stratified_samples");
  require_samples(c.depth_samples, 0, "depth_samples");
  require_samples(c.eval_coarse_samples, 1, "eval_coarse_samples");
  require_samples(c.eval_fine_samples, 1, "eval_fine_samples");
  require(c.mc_passes <= kMostDropoutPasses,
          "mc_passes must be at most " + std::to_string(kMostDropoutPasses));
  // Adam moves each parameter by about its rate every step: a rate past kMostLearningRate throws the
  // parameters about (the grid's at 1e30 trained to garbage while the loss stayed finite, so the
  // divergence guard never fired). A rate for a group the field has not is a typo ("gird"), which
  // left the group at the default rate without a word.
  const auto rate_ok = [](float lr) { return lr >= 0 && lr <= kMostLearningRate; };  // false for NaN
  const std::string range = "[0, " + std::to_string(int(kMostLearningRate)) + "]";
  require(rate_ok(c.adam.default_lr), "adam.default_lr must be in " + range);
  for (const auto& [name, lr] : c.adam.lr) {
    std::string groups;
    bool known = false;
    for (const char* group : field::kParameterGroups) {
      groups += (groups.empty() ? "" : ", ") + std::string(group);
      known = known || name == group;
    }
    require(known, "adam.lr has no group '" + name + "' (the field's groups: " + groups + ")");
    require(rate_ok(lr), "adam.lr." + name + " must be in " + range + ", got " + std::to_string(lr));
  }
  require(c.adam.beta1 >= 0 && c.adam.beta1 < 1 && c.adam.beta2 >= 0 && c.adam.beta2 < 1,
          "adam.beta1 and adam.beta2 must be in [0, 1)");
  require(c.adam.eps > 0, "adam.eps must be > 0");
  require(c.adam.final_lr_factor >= 0 && c.adam.clip_norm >= 0,
          "adam.final_lr_factor and adam.clip_norm must be >= 0");
  require(c.nll_weight >= 0 && c.rgb_l2_weight >= 0 && c.depth_weight >= 0 && c.variance_reg >= 0,
          "nll_weight, rgb_l2_weight, depth_weight and variance_reg must be >= 0");
  require(c.huber_delta > 0, "huber_delta must be > 0");
  require(c.depth_xi > 0, "depth_xi must be > 0");
  require(c.holdout == 0 || c.holdout >= 2,
          "holdout must be 0 (none held out) or K >= 2 (every K-th frame), got " + std::to_string(c.holdout));
  require(c.depth_loss == "huber" || c.depth_loss == "l1",
          "depth_loss must be huber or l1, got " + c.depth_loss);
  require(c.variance_eps > 0, "variance_eps must be > 0");
  require(c.background == "auto" || c.background == "black" || c.background == "white" ||
              c.background == "learned",
          "background must be auto, black, white or learned, got " + c.background);
  require(
      !c.field.learned_background || c.background == "learned",
      "field.learned_background is set by background \"learned\" only, but background is " + c.background);
  require(c.outside_view == "auto" || c.outside_view == "off",
          "outside_view must be auto or off, got " + c.outside_view);
  require(c.outside_view_level >= 0 && c.outside_view_level <= 254,
          "outside_view_level must be in [0, 254], got " + std::to_string(c.outside_view_level));
  require(c.exposure == "auto" || c.exposure == "on" || c.exposure == "off",
          "exposure must be auto, on or off, got " + c.exposure);
  require(c.exposure_threshold >= 0, "exposure_threshold must be >= 0");
  require(c.still_threshold_px >= 0, "still_threshold_px must be >= 0");
  require(c.deformation_start == "flow" || c.deformation_start == "zero",
          "deformation_start must be flow or zero, got " + c.deformation_start);
  // The field's keys (field.*), checked here, before a clip is loaded; the field's own checks name the
  // key, and a configuration's errors say they are the configuration's.
  try {
    field::CheckFieldConfig(c.field);
  } catch (const Error& e) {
    FailInvalid(std::string("config: ") + e.what());
  }
  // The networks' work, after the field's own checks (a layer wider than the field takes is named
  // there first).
  const double per_sample = field::SampleMultiplyAdds(c.field);
  const double per_step = double(c.rays_per_batch) * (c.depth_samples + c.stratified_samples) * per_sample;
  require(per_step <= kMostStepMultiplyAdds,
          fmt::format("a training step of rays_per_batch {} x {} samples through the field's heads "
                      "(field.heads: about {:.3g} multiply-adds a sample) is about {:.3g} multiply-adds, "
                      "more than {:.3g}: fewer rays or samples, or smaller heads",
                      c.rays_per_batch, c.depth_samples + c.stratified_samples, per_sample, per_step,
                      kMostStepMultiplyAdds));
  const double per_pixel =
      double(c.eval_coarse_samples + c.eval_fine_samples) * (c.mc_passes + 1) * per_sample;
  require(per_pixel <= kMostPixelMultiplyAdds,
          fmt::format("an evaluated pixel of {} + {} samples (eval_coarse_samples, eval_fine_samples) in "
                      "mc_passes {} + 1 passes is about {:.3g} multiply-adds, more than {:.3g}: fewer "
                      "samples or passes, or smaller heads",
                      c.eval_coarse_samples, c.eval_fine_samples, c.mc_passes, per_pixel,
                      kMostPixelMultiplyAdds));
  require(c.nll_beta >= 0 && c.nll_beta <= 1, "nll_beta must be in [0, 1]");
  require(c.curve_interval_s > 0, "curve_interval_s must be > 0");
  require(c.mc_passes >= 0, "mc_passes must be >= 0");
  require(c.uncertainty_lambda >= 0, "uncertainty_lambda must be >= 0");
  require(c.adaptive_warmup >= 0 && c.adaptive_warmup <= 1, "adaptive_warmup must be in [0, 1]");
  require(c.adaptive_ray_fraction >= 0 && c.adaptive_ray_fraction <= 1,
          "adaptive_ray_fraction must be in [0, 1]");
  require(c.adaptive_refresh >= 1 && c.adaptive_map_stride >= 1,
          "adaptive_refresh and adaptive_map_stride must be >= 1");
  require(c.adaptive_floor > 0 && c.adaptive_floor <= 1, "adaptive_floor must be in (0, 1]");
  require(c.depth_refine_every >= 0 && c.depth_refine_every <= 1, "depth_refine_every must be in [0, 1]");
  require(c.depth_refine_fraction > 0 && c.depth_refine_fraction <= 1,
          "depth_refine_fraction must be in (0, 1]");
  require(c.depth_refine_ema > 0 && c.depth_refine_ema <= 1, "depth_refine_ema must be in (0, 1]");
  require(c.depth_refine_samples >= 1, "depth_refine_samples must be >= 1");
  require(c.depth_refine_pixels >= 0, "depth_refine_pixels must be >= 0");
  require(c.depth_fill_sigma >= 0 && c.depth_fill_sigma <= 50, "depth_fill_sigma must be in [0, 50]");
  require(c.occupancy_resolution >= 0 && c.occupancy_resolution <= 512,
          "occupancy_resolution must be in [0, 512]");
  require(c.occupancy_every > 0 && c.occupancy_every <= 1, "occupancy_every must be in (0, 1]");
  require(c.occupancy_min_alpha > 0 && c.occupancy_min_alpha < 1, "occupancy_min_alpha must be in (0, 1)");
}

}  // namespace

void BackgroundColor(const TrainConfig& config, float (&rgb)[3]) {
  const float v = config.background == "white" ? 1.0f : 0.0f;
  rgb[0] = rgb[1] = rgb[2] = v;
}

namespace {

// A float as the shortest decimal that reads back as it (0.9, not 0.8999999761581421 as its double
// has it; config.json and the report showed the latter).
double ShortestDecimal(float value) {
  if (!std::isfinite(value)) return value;
  const std::string text = fmt::format("{}", value);  // the shortest that reads back as `value`
  double shortest = value;
  std::from_chars(text.data(), text.data() + text.size(), shortest);  // locale-free, unlike stod
  return shortest;
}

template <typename T>
nlohmann::json ConfigValue(const T& value) {
  if constexpr (std::is_same_v<T, float>) {
    return ShortestDecimal(value);
  } else if constexpr (std::is_same_v<T, std::map<std::string, float>>) {
    nlohmann::json object = nlohmann::json::object();
    for (const auto& [name, number] : value) object[name] = ShortestDecimal(number);
    return object;
  } else if constexpr (std::is_same_v<T, std::vector<float>> || std::is_same_v<T, std::array<float, 2>>) {
    nlohmann::json array = nlohmann::json::array();
    for (const float number : value) array.push_back(ShortestDecimal(number));
    return array;
  } else {
    return value;
  }
}

}  // namespace

nlohmann::json ToJson(const TrainConfig& config) {
  nlohmann::json json;
  TrainConfig copy = config;
  VisitKeys(copy, [&](const char* key, auto& value) { json[Pointer(key)] = ConfigValue(value); });
  return json;
}

void ApplyJson(const nlohmann::json& json, TrainConfig& config) {
  if (!json.is_object()) FailInvalid("config: expected a JSON object");
  if (json.empty()) return Validate(config);
  const nlohmann::json flat = json.flatten();
  std::size_t used = 0;
  VisitKeys(config, [&](const char* key, auto& value) {
    const auto pointer = Pointer(key);
    if (!json.contains(pointer)) return;
    RequireFits<std::remove_cvref_t<decltype(value)>>(json.at(pointer), key);
    try {
      using T = std::remove_cvref_t<decltype(value)>;
      if constexpr (requires { typename T::mapped_type; }) {
        // A map merges: {"adam": {"lr": {"grid": 0.05}}} changes one rate and keeps the others.
        for (auto& [name, entry] : json.at(pointer).template get<T>()) value[name] = entry;
      } else {
        json.at(pointer).get_to(value);
      }
    } catch (const nlohmann::json::exception& e) {
      FailInvalid(std::string("config: bad value for ") + key + ": " + e.what());
    }
    const auto& node = json.at(pointer);
    used += node.is_structured() && !node.empty() ? node.flatten().size() : 1;
  });
  if (used != flat.size()) {
    // Name the first key nobody read.
    for (const auto& item : flat.items()) {
      const std::string& path = item.key();  // not a structured binding: clang 14 cannot capture one
      bool known = false;
      TrainConfig probe;
      VisitKeys(probe, [&](const char* key, auto&) {
        const std::string prefix = Pointer(key).to_string();
        if (path == prefix || path.rfind(prefix + "/", 0) == 0) known = true;
      });
      if (!known) {
        FailInvalid("config: unknown key " + (path.size() > 200 ? path.substr(0, 200) + "..." : path));
      }
    }
  }
  Validate(config);
}

void CheckConfigJson(const nlohmann::json& config, const std::string& preset) {
  TrainConfig resolved = TrainConfig::Preset(preset);
  ApplyJson(config, resolved);
}

}  // namespace endorecon::train
