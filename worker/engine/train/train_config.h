// Everything a training run needs, as one value that is written to config.json beside every
// result and can be read back to reproduce it. Three presets: "paper" (the paper's settings), "cpu"
// (sized for a 2-core machine: a small clip in minutes) and "gpu" (the cpu preset with a GPU's batch).
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "worker/engine/field/field.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/train/adam.h"

namespace endorecon::train {

// Bounds a configuration is held to beyond its types (ApplyJson refuses more). The largest batch a
// preset uses is 2,048 rays and the largest measured useful on an H200 12,288 (docs/benchmarks.md);
// the paper's sampler takes 64 + 32 samples a ray and its evaluation 8 dropout passes.
inline constexpr int kMostRaysPerBatch = 65536;
inline constexpr int kMostSamplesPerRay = 1024;
inline constexpr int kMostDropoutPasses = 64;
// The networks' work a configuration may ask for (field::SampleMultiplyAdds, an estimate): per
// training step (rays x samples x multiply-adds) and per evaluated pixel (samples x passes x
// multiply-adds). The paper's preset asks for 3.1e9 and 1.8e7 (64-wide heads, 2,048 rays of 96
// samples, 128 samples and 9 passes a pixel); 8 hidden layers of 1,024 units with 65,536 rays did
// not finish one step in three minutes, and a cancel, the budget and SIGTERM wait for a step to end
// (found 2026-12-06).
inline constexpr double kMostStepMultiplyAdds = 64e9;
inline constexpr double kMostPixelMultiplyAdds = 2e8;
// Adam's rates at most (the presets' largest is the grid's 3e-2).
inline constexpr float kMostLearningRate = 1.0f;

struct TrainConfig {
  std::string preset = "cpu";
  int iterations = 4000;
  int rays_per_batch = 1024;
  // Training samples per ray: Gaussian around the depth prior plus stratified over [near, far].
  // Without depth every sample is stratified.
  int depth_samples = 16;
  int stratified_samples = 8;
  double depth_xi = 0.02;  // width of the Gaussian, as a fraction of far - near
  int holdout = 8;         // every K-th frame held out of training; 0 = none

  // Loss (paper §3 "Training Objective" + EndoNeRF's rendered-colour L2, see losses.h).
  // The paper's uncertainty-loss weight (lambda_unc = 0.02-0.03); the CPU preset uses 0.0075. At 1
  // the NLL's 1/sigma^2 (down to 1/variance_eps) outweighs the photometric term. With the variance
  // floor at 1e-6 the NLL ranks errors well and pulls harder on the mean colours, so less weight buys
  // PSNR back: demo clip, 300 s, held-out PSNR / Spearman (single runs): 0.02 -> 36.99 dB / 0.68,
  // 0.01 -> 37.17-37.25 / 0.65-0.66, 0.0075 -> 37.54 / 0.64, 0.005 -> 37.54 / 0.59, against the
  // neighbour baseline's 37.34 dB (docs/benchmarks.md, "The variance floor").
  float nll_weight = 0.02f;
  // 0: the paper's NLL; beta > 0: beta-NLL (train/losses.h), each sample's NLL weighted by its variance^beta.
  float nll_beta = 0.0f;
  float rgb_l2_weight = 1.0f;
  float depth_weight = 1.0f;                        // lambda_d
  float variance_reg = 0.03f;                       // eta
  std::string depth_loss = "l1";                    // "l1" or "huber", on depth in units of far - near
  float huber_delta = 0.05f;                        // in units of far - near
  float variance_eps = field::kDefaultVarianceEps;  // eps in var = softplus(l) + eps (variance.h)

  AdamConfig adam;

  // Rendering at evaluation: coarse stratified pass, then importance samples from its weights.
  int eval_coarse_samples = 48;
  int eval_fine_samples = 48;
  float eval_floor = 0.02f;  // share of fine samples spread uniformly along the ray

  // Uncertainty (paper §3). At evaluation: K dropout passes; lambda weighs the colour variance
  // (colour², colours in [0, 1]) against the density variance (density², far larger) in the ray
  // score. Measured on the synthetic demo clip (20 s of training, K = 4), mean Spearman against the
  // per-pixel error: lambda 1 -> -0.32 (the density term dominates), 1e4 -> 0.20, 1e6 -> 0.49. With
  // longer training the densities (and their variance across dropout passes, in density^2) grow:
  // at 2500 iterations lambda 1e6 gave 0.30 (the density's epistemic part, anti-correlated with the
  // error, dominates) and 1e12 gave 0.57, so the colour variance carries the score.
  int mc_passes = 8;
  float uncertainty_lambda = 1e12f;
  // Uncertainty-guided adaptive sampling in training (docs/architecture.md). After the warm-up (a
  // fraction of the run: of the iterations, or of the time budget when there is one), a fraction of
  // each batch's rays is drawn in proportion to a per-pixel uncertainty map of the training frames
  // (one dropout-on pass over every adaptive_map_stride-th pixel in x and y, refreshed every
  // adaptive_refresh iterations); those rays' samples are reallocated by their sample scores from one
  // dropout-on pass at the ordinary samples, with a uniform floor.
  bool adaptive_sampling = true;
  double adaptive_warmup = 0.1;
  float adaptive_ray_fraction = 0.3f;
  int adaptive_refresh = 500;
  int adaptive_map_stride = 4;
  float adaptive_floor = 0.2f;

  // EndoNeRF's depth-prior refinement (train/depth_refiner.h): a round every depth_refine_every of
  // the run (of the iterations, or of the time budget), moving the depth_refine_fraction of each
  // training frame's priors that disagree most with the rendered depth towards it by the moving
  // average depth_refine_ema; rendered with depth_refine_samples coarse and as many fine samples.
  // The paper: every 4000 of 50k iterations (0.08), alpha = 0.1; EndoNeRF: the worst 10%, every frame
  // in a round. The CPU preset runs 3 rounds of 100k pixels (~1 s each on the demo clip; a round of
  // every frame took ~6 s).
  double depth_refine_every = 0.08;  // 0: off
  float depth_refine_fraction = 0.1f;
  float depth_refine_ema = 0.1f;
  int depth_refine_samples = 24;
  int depth_refine_pixels = 0;  // measured pixels rendered per round (frames in turn); 0: every frame
  // Holes in the training frames' depth priors (where stereo failed: highlights mostly) filled from
  // the measured depths around them before training, a Gaussian of depth_fill_sigma pixels
  // (train/depth_fill.h); 0: off. Holes next to the tool stay.
  double depth_fill_sigma = 2;

  // Empty-space skipping (render/occupancy_grid.h): a grid of occupancy_resolution^3 cells rebuilt
  // from the field every occupancy_every of the run; stratified samples cover only each ray's occupied
  // span. A cell counts as empty when a sample one cell long would be less than occupancy_min_alpha
  // opaque at every probed time.
  int occupancy_resolution = 48;  // 0: off
  double occupancy_every = 0.2;
  float occupancy_min_alpha = 0.01f;

  // What a ray sees past its samples: "black" (an endoscope's dark beyond the light), "white" (object
  // captures on white, NeRF-synthetic's convention), "learned" (a colour per ray direction learned
  // with the field, field/background.h: a capture in front of a backdrop, a room; transparent pixels
  // are still read onto white), or "auto": white when the clip's images had transparent pixels
  // (composited onto white as they are read), learned for an object capture (a centred rig) with
  // opaque images, black otherwise (an endoscope). FitToScene resolves "auto", so config.json records
  // the background used, and sets field.learned_background for "learned".
  std::string background = "auto";

  // The part of an endoscope's frames outside its round view (scene/outside_view.h): "auto" leaves
  // it out of training and evaluation (as a tool is) where the frames have one, "off" keeps every
  // pixel. outside_view_level: how dark (brightest channel, of 255) such a pixel stays in every frame.
  std::string outside_view = "auto";
  int outside_view_level = 8;

  // Per-frame camera exposure apart from the tissue's colour (field/exposure.h): "on" (a gain per
  // colour channel at each training frame's time, learned with the field), "off", or "auto": on
  // when the training frames' brightness changes by more than exposure_threshold (the median over
  // neighbouring frames of the whole-frame shift in log intensity, scene/exposure_change.h).
  // FitToScene resolves "auto" and fills field.exposure_times.
  std::string exposure = "auto";
  double exposure_threshold = 0.02;

  // A clip whose times differ but whose tissue stands still gets no deformation: FitToScene leaves it
  // out when, with the camera fixed, 95% of the tissue moves less than this many pixels from the
  // first training frame in every other (train/still_clip.h). 0: never.
  double still_threshold_px = 0.25;
  // Depth bounds far looser than the clip's depth priors, or cutting them off, are brought to the
  // priors' range when the clip is loaded (scene/depth_bounds.h); false: as the clip gives them.
  bool fit_depth_bounds = true;

  // Where the deformation starts (train/flow_start.h): "flow" (fitted to the optical flow from each
  // training frame back to the frame at time 0, where the clip has depth and such a frame) or "zero"
  // (no motion until the photometric loss finds some).
  std::string deformation_start = "flow";

  double curve_interval_s = 10.0;  // the error-against-time curve's points: at most this far apart
                                   // (closer early on: train/run_clock.h, CurveTimes)
  int curve_frames = 4;            // held-out frames rendered for each curve point (evenly spread)

  field::FieldConfig field;

  static TrainConfig Preset(const std::string& name);  // throws Error(kInvalidArgument) for unknown names
};

// Writes the background's RGB in [0, 1] to rgb ("auto" before FitToScene resolves it, and "learned",
// whose colour is the field's: black).
void BackgroundColor(const TrainConfig& config, float (&rgb)[3]);

nlohmann::json ToJson(const TrainConfig& config);
// Overrides the keys present in `json` (same names as ToJson); unknown keys are an error naming them.
void ApplyJson(const nlohmann::json& json, TrainConfig& config);

}  // namespace endorecon::train
