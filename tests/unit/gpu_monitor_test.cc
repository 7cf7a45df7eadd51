// NVML loaded at run time: without the NVIDIA driver (this development machine) the monitor is
// absent and says why; with it, a bus id no device has reads nothing.
#include "worker/runtime/gpu_monitor.h"

#include <gtest/gtest.h>

namespace endorecon::worker {
namespace {

TEST(GpuMonitorTest, AbsentWithItsReasonOrReadsOnlyRealDevices) {
  std::string problem;
  const auto monitor = GpuMonitor::Open(problem);
  if (!monitor) {
    EXPECT_FALSE(problem.empty());
    EXPECT_TRUE(problem.find("libnvidia-ml.so.1") != std::string::npos ||
                problem.find("nvmlInit") != std::string::npos)
        << problem;
    return;
  }
  EXPECT_TRUE(problem.empty()) << problem;
  EXPECT_FALSE(monitor->Read("ffff:ff:1f.0").has_value());
}

}  // namespace
}  // namespace endorecon::worker
