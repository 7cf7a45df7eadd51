#include "worker/engine/cuda/device.h"

#include <gtest/gtest.h>

#include <vector>

#include "common/error.h"

namespace endorecon::cuda {
namespace {

TEST(CudaDeviceTest, ListsTheDevicesOrSaysWhyThereAreNone) {
  const DeviceList list = ListDevices();
  EXPECT_EQ(static_cast<int>(list.devices.size()), DeviceCount());
  if (list.devices.empty()) {
    EXPECT_FALSE(list.problem.empty()) << "no device and no reason given";
    return;
  }
  for (std::size_t i = 0; i < list.devices.size(); ++i) {
    const DeviceInfo& d = list.devices[i];
    EXPECT_EQ(d.index, static_cast<int>(i));
    EXPECT_FALSE(d.name.empty());
    EXPECT_GE(d.compute_major, 3);
    EXPECT_GT(d.multiprocessors, 0);
    EXPECT_GT(d.total_memory_bytes, 0u);
  }
}

TEST(CudaDeviceTest, RejectsADeviceIndexThatDoesNotExist) {
  try {
    SetDevice(DeviceCount());
    FAIL() << "SetDevice accepted an index past the last device";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SetDevice(-1), Error);
}

TEST(CudaDeviceTest, AllocationWithoutADeviceIsAnErrorNotACrash) {
  if (DeviceCount() > 0) GTEST_SKIP() << "a device is present";
  try {
    DeviceArray<float> a(1024);
    FAIL() << "allocated device memory without a device";
  } catch (const Error& e) {
    EXPECT_NE(e.code(), ErrorCode::kInternal) << e.what();
    EXPECT_NE(std::string(e.what()).find("cudaMalloc"), std::string::npos) << e.what();
  }
}

TEST(CudaDeviceTest, ArraysRoundTripAndCheckSizes) {
  if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
  SetDevice(0);
  const std::size_t total = ListDevices().devices[0].total_memory_bytes;
  const std::size_t free_before = FreeMemoryBytes();
  EXPECT_GT(free_before, 0u);
  EXPECT_LE(free_before, total);
  const std::vector<float> host = {1.5f, -2.0f, 3.25f};
  DeviceArray<float> a(host);
  EXPECT_EQ(a.Download(), host);
  a.Zero();
  EXPECT_EQ(a.Download(), std::vector<float>(3, 0.0f));
  try {
    a.Upload(std::vector<float>(4));
    FAIL() << "uploaded 4 values into an array of 3";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
  }
  DeviceArray<float> b(std::move(a));
  EXPECT_EQ(a.data(), nullptr);
  EXPECT_EQ(b.size(), 3u);
}

}  // namespace
}  // namespace endorecon::cuda
