#include "worker/runtime/device_list.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"

namespace endorecon::worker {
namespace {

TEST(DeviceList, CpuSlotsShareTheCores) {
  const auto one = ParseDevices("cpu", 0, 8);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].name, "cpu0");
  EXPECT_EQ(one[0].kind, "cpu");
  EXPECT_EQ(one[0].threads, 8);
  const auto three = ParseDevices("cpu:3", 0, 8);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_EQ(three[2].name, "cpu2");
  for (const auto& d : three) EXPECT_EQ(d.threads, 2);
  EXPECT_EQ(ParseDevices("cpu:4", 0, 2)[3].threads, 1);  // never fewer than one
  EXPECT_EQ(ParseDevices("cpu:2", 5, 2)[1].threads, 5);  // --threads wins
}

TEST(DeviceList, GpuIndicesAreCudaEnginesOneEach) {
  const auto gpus = ParseDevices("0,2", 0, 8);
  ASSERT_EQ(gpus.size(), 2u);
  EXPECT_EQ(gpus[1].name, "gpu2");
  EXPECT_EQ(gpus[1].kind, "cuda");
  EXPECT_EQ(gpus[1].index, 2);
  EXPECT_EQ(gpus[1].EngineDevice(), "cuda:2");
  EXPECT_EQ(gpus[0].threads, 4);
  EXPECT_EQ(ParseDevices("cpu", 0, 2)[0].EngineDevice(), "cpu");
}

// A GPU that is not there is refused at start naming it, never run on the CPU instead (this machine
// has no device 99, with or without a CUDA build).
TEST(DeviceList, AGpuThatCannotRunIsRefusedNamingIt) {
  auto cpus = ParseDevices("cpu:2", 0, 2);
  DescribeDevices(cpus);
  EXPECT_EQ(cpus[1].description.kind, "cpu");
  EXPECT_FALSE(cpus[1].description.model.empty());
  EXPECT_GT(cpus[1].description.memory_bytes, 0);
  auto missing = ParseDevices("99", 0, 2);
  try {
    DescribeDevices(missing);
    FAIL() << "accepted CUDA device 99";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("cuda:99"), std::string::npos) << e.what();
  }
}

TEST(DeviceList, BadFormsAreRefusedNamingTheFlag) {
  for (const std::string bad : {"cpu:0", "cpu:", "cpu:x", "cpu:-1", "gpu", "0,,1", "1,a", "", "cpu:99999"}) {
    try {
      ParseDevices(bad, 0, 2);
      ADD_FAILURE() << "accepted --devices " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << bad;
      EXPECT_NE(std::string(e.what()).find("--devices " + bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace endorecon::worker
