// cuda::DeviceMlp against the CPU field::Mlp it mirrors: outputs, the input gradient and every
// parameter's gradient, for a head-sized network (its weights staged in shared memory for the input
// gradient) and a wide one (read from global memory), with dropout on.
#include "worker/engine/cuda/device_mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "worker/engine/cuda/device.h"
#include "worker/engine/field/mlp.h"

namespace endorecon::cuda {
namespace {

// |a - b| <= tol * max(1, |b|), naming the first few that differ.
void ExpectClose(const std::vector<float>& gpu, const std::vector<float>& cpu, float tol, const char* what) {
  ASSERT_EQ(gpu.size(), cpu.size()) << what;
  int bad = 0;
  for (std::size_t i = 0; i < cpu.size() && bad < 5; ++i) {
    if (!(std::fabs(gpu[i] - cpu[i]) <= tol * std::fmax(1.0f, std::fabs(cpu[i])))) {
      ADD_FAILURE() << what << "[" << i << "]: gpu " << gpu[i] << ", cpu " << cpu[i];
      ++bad;
    }
  }
}

struct Shape {
  int in, hidden, out;
};

class DeviceMlpTest : public ::testing::TestWithParam<Shape> {
 protected:
  void SetUp() override {
    if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
    SetDevice(0);
  }

  std::vector<float> Uniform(std::size_t n) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> v(n);
    for (float& x : v) x = u(rng_);
    return v;
  }

  std::mt19937 rng_{20261204};
};

TEST_P(DeviceMlpTest, ForwardAndBackwardMatchTheCpuMlp) {
  const Shape shape = GetParam();
  const int n = 3001;  // no multiple of a block, a chunk or a tile
  field::Mlp<float> mlp(shape.in, {shape.hidden}, shape.out, 0.1, 3);
  std::vector<float> params(mlp.param_count());
  mlp.Init(params.data(), 7);
  const std::vector<float> x = Uniform(std::size_t(n) * shape.in), dy = Uniform(std::size_t(n) * shape.out);
  const field::DropoutPass pass{true, 99, 0};

  std::vector<float> hidden(std::size_t(n) * shape.hidden), y(std::size_t(n) * shape.out),
      dx(std::size_t(n) * shape.in), dparams(params.size(), 0.0f);
  float* hidden_ptr[] = {hidden.data()};
  mlp.Forward(params.data(), {n, x.data()}, {hidden_ptr, y.data()}, pass);
  mlp.Backward(params.data(), {n, x.data()}, {hidden_ptr, y.data()}, {dy.data()}, dparams.data(), {dx.data()},
               pass);

  const DeviceMlp device(mlp);
  DeviceArray<float> d_params(params), d_x(x), d_dy(dy), d_hidden(hidden.size()), d_y(y.size()),
      d_dx(dx.size()), d_dparams(params.size()), d_scratch(device.scratch_size(n));
  d_dparams.Zero();
  float* d_hidden_ptr[] = {d_hidden.data()};
  device.Forward(d_params.data(), d_x.data(), n, d_hidden_ptr, d_y.data(), pass);
  device.Backward(d_params.data(), d_x.data(), n, d_hidden_ptr, d_dy.data(), d_dx.data(), d_dparams.data(),
                  d_scratch.data(), pass);
  Synchronize();
  ExpectClose(d_y.Download(), y, 1e-4f, "output");
  ExpectClose(d_dx.Download(), dx, 1e-4f, "input gradient");
  // Sums over 3,001 rows in another order: rounding grows with the row count.
  ExpectClose(d_dparams.Download(), dparams, 1e-3f, "parameter gradient");
}

// 39 -> 32 -> 4: the colour head's shape (weights in shared memory); 100 -> 128 -> 70: layers of more
// than 8,192 weights (read from global memory).
INSTANTIATE_TEST_SUITE_P(HeadAndWide, DeviceMlpTest,
                         ::testing::Values(Shape{39, 32, 4}, Shape{100, 128, 70}));

}  // namespace
}  // namespace endorecon::cuda
