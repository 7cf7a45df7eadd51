// The field on the GPU against the field on the CPU, module by module through the whole composition:
// the same outputs and the same gradient of every block, up to float rounding (fused multiply-adds,
// atomics summing in any order, the device's transcendentals). Skipped without a GPU.
#include "worker/engine/cuda/device_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/cuda/field_difference.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_adam.h"
#include "worker/engine/train/adam.h"

namespace endorecon::cuda {
namespace {

class DeviceFieldTest : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
    SetDevice(0);
  }
};

field::FieldConfig Config(bool deformation) {
  field::FieldConfig c = field::FieldConfig::Cpu();
  c.deformation.enabled = deformation;
  c.exposure_times = {0.1f, 0.3f, 0.5f, 0.7f, 0.9f};  // the exposure's kernels too
  return c;
}

struct Samples {
  int n;
  std::vector<float> pos, time, dir, d_sigma, d_rgb, d_rgb_lv;
  explicit Samples(int count) : n(count) {
    std::mt19937 gen(5);
    std::uniform_real_distribution<float> u(0.02f, 0.98f), g(-1.0f, 1.0f);
    for (int i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) pos.push_back(u(gen));
      time.push_back(u(gen));
      const float d[3] = {g(gen), g(gen), -1.0f};
      const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (float x : d) dir.push_back(x / len);
      d_sigma.push_back(g(gen));
      for (int c = 0; c < 3; ++c) d_rgb.push_back(g(gen));
      d_rgb_lv.push_back(g(gen));
    }
  }
};

TEST_P(DeviceFieldTest, OutputsAndEveryGradientMatchTheCpuField) {
  field::Field host(Config(GetParam()), 3);
  // Non-trivial parameters everywhere (the deformation and the blend's output layer start at zero).
  std::mt19937 gen(9);
  std::uniform_real_distribution<float> u(-0.05f, 0.05f);
  for (auto& b : host.Blocks()) {
    for (std::size_t i = 0; i < b.size; ++i) b.value[i] += b.name == "deform" ? 0.1f * u(gen) : u(gen);
  }
  DeviceField device(host);
  const Samples s(20000);
  std::vector<float> sigma(s.n), sigma_lv(s.n), rgb(3 * s.n), rgb_lv(s.n);
  field::FieldOutput out{sigma.data(), sigma_lv.data(), rgb.data(), rgb_lv.data()};
  const field::SampleBatch batch{s.n, s.pos.data(), s.time.data(), s.dir.data()};
  host.Forward(batch, out, true, 77);
  host.ZeroGrad();
  host.Backward(batch, {s.d_sigma.data(), nullptr, s.d_rgb.data(), s.d_rgb_lv.data()});

  DeviceArray<float> pos(s.pos), time(s.time), dir(s.dir), d_sigma(s.d_sigma), d_rgb(s.d_rgb),
      d_rgb_lv(s.d_rgb_lv);
  DeviceArray<float> g_sigma(s.n), g_sigma_lv(s.n), g_rgb(3 * s.n), g_rgb_lv(s.n);
  field::FieldOutput g_out{g_sigma.data(), g_sigma_lv.data(), g_rgb.data(), g_rgb_lv.data()};
  const field::SampleBatch g_batch{s.n, pos.data(), time.data(), dir.data()};
  device.Forward(g_batch, g_out, true, 77);
  device.ZeroGrad();
  device.Backward(g_batch, {d_sigma.data(), nullptr, d_rgb.data(), d_rgb_lv.data()});
  Synchronize();
  EXPECT_LT(RelativeDifference(g_sigma.Download(), sigma), 1e-4) << "densities";
  EXPECT_LT(RelativeDifference(g_rgb.Download(), rgb), 1e-4) << "colours";
  EXPECT_LT(RelativeDifference(g_rgb_lv.Download(), rgb_lv), 1e-4) << "colour log-variances";
  ExpectSameGradients(host, device);
}

TEST_P(DeviceFieldTest, DecodeOfEncodeIsInferAndParametersMoveBothWays) {
  field::Field host(Config(GetParam()), 4);
  DeviceField device(host);
  const Samples s(3000);
  DeviceArray<float> pos(s.pos), time(s.time), dir(s.dir), enc(std::size_t(s.n) * device.encoding_dim());
  DeviceArray<float> a(3 * s.n), b(3 * s.n), x(s.n), y(s.n), z(s.n), w(s.n);
  const field::SampleBatch batch{s.n, pos.data(), time.data(), dir.data()};
  field::FieldOutput oa{x.data(), y.data(), a.data(), z.data()}, ob{x.data(), y.data(), b.data(), w.data()};
  device.Infer(batch, oa, true, 5);
  device.Encode(batch, enc.data());
  device.Decode(enc.data(), batch, ob, true, 5);
  EXPECT_EQ(a.Download(), b.Download());
  // A null rgb: the density alone, the same as with the colour.
  DeviceArray<float> x2(s.n), y2(s.n);
  field::FieldOutput density_only{x2.data(), y2.data(), nullptr, nullptr};
  device.Infer(batch, density_only, true, 5);
  EXPECT_EQ(x2.Download(), x.Download());
  EXPECT_EQ(y2.Download(), y.Download());
  // Download and Upload move the parameters between the host field and the device unchanged.
  const float before = host.Blocks()[0].value[7];
  host.Blocks()[0].value[7] = 123.0f;
  device.Download();
  EXPECT_EQ(host.Blocks()[0].value[7], before);
  host.Blocks()[0].value[7] = 0.5f;
  device.Upload();
  float on_device = 0;
  CopyToHost(&on_device, device.Blocks()[0].value + 7, sizeof(float));
  EXPECT_EQ(on_device, 0.5f);
}

TEST_P(DeviceFieldTest, AdamStepMatchesTheCpuOptimiser) {
  field::Field host(Config(GetParam()), 6);
  DeviceField device(host);
  train::AdamConfig config;
  config.lr = {{"grid", 1e-2f}};
  train::Adam cpu(host.Blocks(), config);
  DeviceAdam gpu(device.Blocks(), config);
  std::mt19937 gen(2);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (auto& b : host.Blocks()) {
    for (std::size_t i = 0; i < b.size; ++i) b.grad[i] = u(gen);
  }
  const auto hb = host.Blocks();
  const auto db = device.Blocks();
  for (std::size_t k = 0; k < hb.size(); ++k)
    CopyToDevice(db[k].grad, hb[k].grad, hb[k].size * sizeof(float));
  EXPECT_TRUE(cpu.Step(0.3).finite);
  EXPECT_TRUE(gpu.Step(0.3).finite);
  for (std::size_t k = 0; k < hb.size(); ++k) {
    std::vector<float> v(db[k].size);
    CopyToHost(v.data(), db[k].value, v.size() * sizeof(float));
    EXPECT_LT(RelativeDifference(v, std::vector<float>(hb[k].value, hb[k].value + hb[k].size)), 1e-5)
        << hb[k].name;
  }
  // A non-finite gradient is refused before any update, naming its block.
  const float nan = std::nanf("");
  CopyToDevice(db[0].grad, &nan, sizeof(float));
  const train::AdamStepReport report = gpu.Step(0.4);
  EXPECT_FALSE(report.finite);
  EXPECT_EQ(report.bad_group, db[0].name);
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutDeformation, DeviceFieldTest, ::testing::Bool());

}  // namespace
}  // namespace endorecon::cuda
