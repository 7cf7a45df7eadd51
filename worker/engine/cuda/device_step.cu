#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_adam.h"
#include "worker/engine/cuda/device_field.h"
#include "worker/engine/cuda/device_step.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/cuda/shared_fields.h"
#include "worker/engine/cuda/step_phases.h"
#include "worker/engine/train/step_math.h"

namespace endorecon::cuda {
namespace {

// Uploads host frames (count arrays of `each` elements) into one device array and gives the device
// pointers of the frames as a device array.
template <typename T>
struct DeviceFrames {
  DeviceArray<T> data;
  DeviceArray<const T*> pointers;

  void Upload(const std::vector<const T*>& frames, std::size_t each) {
    if (data.size() != frames.size() * each) data = DeviceArray<T>(frames.size() * each);
    std::vector<const T*> device(frames.size());
    for (std::size_t f = 0; f < frames.size(); ++f) {
      CopyToDevice(data.data() + f * each, frames[f], each * sizeof(T));
      device[f] = data.data() + f * each;
    }
    if (pointers.size() != frames.size()) pointers = DeviceArray<const T*>(frames.size());
    pointers.Upload(device);
  }
};

// Marks the field's module phases in `phases` while it lives: the field may outlive the step (it can
// be shared with the run's renderers), so it never keeps the pointer past a step, thrown or not.
class FieldPhases {
 public:
  FieldPhases(DeviceField& field, StepPhases& phases) : field_(field) { field_.SetPhases(&phases); }
  ~FieldPhases() { field_.SetPhases(nullptr); }
  FieldPhases(const FieldPhases&) = delete;
  FieldPhases& operator=(const FieldPhases&) = delete;

 private:
  DeviceField& field_;
};

template <typename T>
DeviceArray<T> Copy(const T* host, std::size_t n) {
  DeviceArray<T> array(n);
  if (n > 0) CopyToDevice(array.data(), host, n * sizeof(T));
  return array;
}

class DeviceStep final : public train::StepBackend {
 public:
  DeviceStep(int index, std::shared_ptr<DeviceField> field, const train::TrainConfig& config,
             const train::StepTables& tables)
      : index_(index), host_(tables), field_(std::move(field)), adam_(field_->Blocks(), config.adam) {
    name_ = DeviceName(index);
    const train::StepTables& t = host_;
    const int frames = t.frames;
    const std::size_t pixels = static_cast<std::size_t>(t.picks.width) * t.picks.height;
    std::vector<const std::uint8_t*> rgb(t.rays.rgb, t.rays.rgb + frames);
    rgb_.Upload(rgb, 3 * pixels);
    if (t.picks.masks) {
      std::vector<const std::uint8_t*> masks(t.picks.masks, t.picks.masks + frames);
      masks_.Upload(masks, pixels);
      occlusion_ = Copy(t.picks.occlusion, pixels);
    }
    train_frames_ = Copy(t.picks.frames, static_cast<std::size_t>(t.picks.frame_count));
    views_ = Copy(t.rays.views, static_cast<std::size_t>(frames));
    times_ = Copy(t.rays.times, static_cast<std::size_t>(frames));
    pixels_ = pixels;
    frames_ = frames;
    AllocateBatch(t.rays_per_batch, t.samples);
    TablesChanged();
  }

  std::string device() const override { return name_; }

  void TablesChanged() override {
    SetDevice(index_);
    const train::StepTables& t = host_;
    device_ = t;
    device_.picks.frames = train_frames_.data();
    device_.picks.occlusion = t.picks.occlusion ? occlusion_.data() : nullptr;
    device_.picks.masks = t.picks.masks ? masks_.pointers.data() : nullptr;
    device_.rays.rgb = rgb_.pointers.data();
    device_.rays.views = views_.data();
    device_.rays.times = times_.data();
    device_.background_params = field::BlockValues(field_->Blocks(), "background");
    if (t.rays.priors) {
      priors_.Upload(std::vector<const float*>(t.rays.priors, t.rays.priors + frames_), pixels_);
      device_.rays.priors = priors_.pointers.data();
    }
    if (t.rays.occupancy.cells) {
      const std::size_t cells =
          static_cast<std::size_t>(t.rays.occupancy.res) * t.rays.occupancy.res * t.rays.occupancy.res;
      occupancy_ = Copy(t.rays.occupancy.cells, cells);
      device_.rays.occupancy.cells = occupancy_.data();
    }
    if (t.map.cells > 0) {
      probes_ = Copy(t.map.probes, static_cast<std::size_t>(t.map.cells));
      cumulative_ = Copy(t.map.cumulative, static_cast<std::size_t>(t.map.cells));
      device_.map.probes = probes_.data();
      device_.map.cumulative = cumulative_.data();
    }
  }

  train::StepResult Step(const train::StepRequest& request) override {
    SetDevice(index_);
    const train::StepTables t = device_;
    const train::StepBatch b = batch_;
    const int guided = request.guided;
    const std::uint64_t seed = request.step_seed;
    phases_.Start();
    ForEach(
        b.rays,
        [=] __device__(std::size_t r) { train::PlaceStepRay(t, b, static_cast<int>(r), guided, seed); },
        "ray placement kernel");
    phases_.Mark("place");
    if (guided > 0) {
      ForEach(
          guided, [=] __device__(std::size_t r) { train::PlaceProbes(t, b, static_cast<int>(r), seed); },
          "probe placement kernel");
      const field::SampleBatch probes{guided * train::ProbeCount(t), b.pos, b.time, b.dir};
      field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
      field_->Infer(probes, out, /*dropout=*/true, base::HashCombine(seed, 0xc0a25eull));
      ForEach(
          guided, [=] __device__(std::size_t r) { train::ReallocateRay(t, b, static_cast<int>(r), seed); },
          "reallocation kernel");
      phases_.Mark("guided");
    }
    const int n = b.rays * b.samples;
    const field::SampleBatch in{n, b.pos, b.time, b.dir};
    field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
    const FieldPhases field_phases(*field_, phases_);  // the field's modules in this step's passes
    field_->Forward(in, out, /*dropout=*/true, request.dropout_seed);
    phases_.Mark("outputs");
    sums_.Zero();
    double* sums = sums_.data();
    ForEach(
        b.rays,
        [=] __device__(std::size_t r) {
          const train::RayStepSums ray = train::RayStepLoss(t, b, static_cast<int>(r));
          atomicAdd(sums, ray.loss);
          atomicAdd(sums + 1, ray.rgb_mse);
        },
        "ray loss kernel");
    phases_.Mark("loss");
    const std::vector<double> host_sums = sums_.Download();
    phases_.Mark("loss readback");
    if (!std::isfinite(host_sums[0])) {
      Fail(ErrorCode::kInternal, "training diverged: the loss is not finite at iteration " +
                                     std::to_string(request.iteration) + " (stage: loss, " + name_ + ")");
    }
    field_->ZeroGrad();
    phases_.Mark("zero grad");
    field_->Backward(in, {b.d_sigma, nullptr, b.d_rgb, b.d_rgb_logvar});
    if (t.background_params) field_->BackgroundBackward(b.rays, b.ray_dir, b.background, b.d_background);
    phases_.Mark("background backward");
    const train::AdamStepReport report = adam_.Step(request.progress);
    phases_.Mark("adam");
    phases_.End();
    if (!report.finite) {
      Fail(ErrorCode::kInternal,
           "training diverged: a gradient is not finite (or its square overflows float) at iteration " +
               std::to_string(request.iteration) + " (stage: backward, group " + report.bad_group + ", " +
               name_ + ")");
    }
    return {host_sums[0], host_sums[1] / b.rays, n};
  }

  std::vector<float> ProbeScores(const std::vector<train::RayPick>& probes, std::uint64_t seed) override {
    SetDevice(index_);
    const train::StepTables t = device_;
    const train::StepBatch b = batch_;
    std::vector<float> scores(probes.size());
    DeviceArray<float> device_scores(static_cast<std::size_t>(b.rays));
    float* out_scores = device_scores.data();
    for (std::size_t start = 0; start < probes.size(); start += static_cast<std::size_t>(b.rays)) {
      const int rays = static_cast<int>(std::min<std::size_t>(b.rays, probes.size() - start));
      CopyToDevice(b.picks, probes.data() + start, rays * sizeof(train::RayPick));
      ForEach(
          rays,
          [=] __device__(std::size_t r) {
            const int i = static_cast<int>(r);
            train::PlaceTrainingRay(t.rays, b.picks[i], seed, i, b.samples, b.target + 3 * i, b.prior + i,
                                    b.camera_rays + i, b.Slot(i, b.samples));
          },
          "probe ray kernel");
      const field::SampleBatch in{rays * b.samples, b.pos, b.time, b.dir};
      field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
      field_->Infer(in, out, /*dropout=*/true, base::HashCombine(seed, start));
      ForEach(
          rays,
          [=] __device__(std::size_t r) { out_scores[r] = train::ProbeRayScore(t, b, static_cast<int>(r)); },
          "probe score kernel");
      CopyToHost(scores.data() + start, out_scores, rays * sizeof(float));
    }
    return scores;
  }

  void Densities(const field::SampleBatch& batch, float* sigma) override {
    SetDevice(index_);
    const std::size_t n = static_cast<std::size_t>(batch.n);
    if (n == 0) return;
    if (density_sigma_.size() < n) {
      density_pos_ = DeviceArray<float>(3 * n);
      density_dir_ = DeviceArray<float>(3 * n);
      density_time_ = DeviceArray<float>(n);
      density_sigma_ = DeviceArray<float>(n);
      density_log_var_ = DeviceArray<float>(n);
    }
    CopyToDevice(density_pos_.data(), batch.pos, 3 * n * sizeof(float));
    CopyToDevice(density_dir_.data(), batch.dir, 3 * n * sizeof(float));
    CopyToDevice(density_time_.data(), batch.time, n * sizeof(float));
    const field::SampleBatch in{batch.n, density_pos_.data(), density_time_.data(), density_dir_.data()};
    field::FieldOutput out{density_sigma_.data(), density_log_var_.data(), nullptr,
                           nullptr};  // density alone
    field_->Infer(in, out, /*dropout=*/false, 0);
    CopyToHost(sigma, density_sigma_.data(), n * sizeof(float));
  }

  void PullField() override {
    SetDevice(index_);
    field_->Download();
  }
  void PushField() override {
    SetDevice(index_);
    field_->Upload();
  }
  void SaveOptimizer(std::ostream& out) const override { adam_.Save(out); }
  void LoadOptimizer(std::istream& in) override { adam_.Load(in); }

 private:
  void AllocateBatch(int rays, int samples) {
    const std::size_t m = static_cast<std::size_t>(rays) * samples;
    auto floats = [&](std::size_t n) {
      arrays_.emplace_back(n);
      return arrays_.back().data();
    };
    batch_.rays = rays;
    batch_.samples = samples;
    batch_.target = floats(3 * static_cast<std::size_t>(rays));
    batch_.prior = floats(rays);
    batch_.s = floats(m);
    batch_.delta = floats(m);
    batch_.pos = floats(3 * m);
    batch_.dir = floats(3 * m);
    batch_.time = floats(m);
    batch_.sigma = floats(m);
    batch_.sigma_logvar = floats(m);
    batch_.rgb = floats(3 * m);
    batch_.rgb_logvar = floats(m);
    batch_.weights = floats(m);
    batch_.d_weights = floats(m);
    batch_.d_sigma = floats(m);
    batch_.d_rgb = floats(3 * m);
    batch_.d_rgb_logvar = floats(m);
    batch_.ray_dir = floats(3 * static_cast<std::size_t>(rays));
    batch_.background = floats(3 * static_cast<std::size_t>(rays));
    batch_.d_background = floats(3 * static_cast<std::size_t>(rays));
    batch_.probe_s = floats(m);
    batch_.probe_delta = floats(m);
    batch_.probe_score = floats(m);
    picks_ = DeviceArray<train::RayPick>(rays);
    camera_rays_ = DeviceArray<render::CameraRay>(rays);
    batch_.picks = picks_.data();
    batch_.camera_rays = camera_rays_.data();
  }

  int index_;
  std::string name_;
  const train::StepTables& host_;       // the Trainer's tables (host pointers)
  train::StepTables device_;            // the same tables with device pointers
  std::shared_ptr<DeviceField> field_;  // perhaps shared with the run's renderers (shared_fields.h)
  DeviceAdam adam_;
  StepPhases phases_;  // off unless ENDORECON_CUDA_STEP_PHASES=1
  DeviceFrames<std::uint8_t> rgb_, masks_;
  DeviceFrames<float> priors_;
  DeviceArray<float> occlusion_;
  DeviceArray<int> train_frames_;
  DeviceArray<scene::PinholeView> views_;
  DeviceArray<float> times_;
  DeviceArray<std::uint8_t> occupancy_;
  DeviceArray<train::RayPick> probes_, picks_;
  DeviceArray<double> cumulative_, sums_{2};
  DeviceArray<render::CameraRay> camera_rays_;
  std::vector<DeviceArray<float>> arrays_;
  // The occupancy probes' points and densities (Densities), sized for the largest batch asked.
  DeviceArray<float> density_pos_, density_dir_, density_time_, density_sigma_, density_log_var_;
  train::StepBatch batch_{};
  std::size_t pixels_ = 0;
  int frames_ = 0;
};

}  // namespace

train::StepBackendFactory DeviceStepFactory(int index, std::shared_ptr<SharedFields> shared) {
  return [index, shared](field::Field& field, const train::TrainConfig& config,
                         const train::StepTables& tables) {
    SetDevice(index);
    return std::unique_ptr<train::StepBackend>(
        new DeviceStep(index, DeviceFieldFor(shared.get(), field), config, tables));
  };
}

}  // namespace endorecon::cuda
