#include "worker/engine/base/machine_memory.h"

#include <gtest/gtest.h>

#include <string>

namespace endorecon::base {
namespace {

// This machine's figures, as /proc/meminfo states them: what is available is some of what there is.
TEST(MachineMemoryTest, AvailableIsSomeOfTheTotal) {
  const std::uint64_t total = TotalMemoryBytes(), available = AvailableMemoryBytes();
  EXPECT_GT(total, std::uint64_t{64} << 20);
  EXPECT_GT(available, 0u);
  EXPECT_LE(available, total);
  EXPECT_EQ(std::to_string(total / 1024) + " kB", ProcFileField("/proc/meminfo", "MemTotal"));
}

TEST(MachineMemoryTest, AFieldNotThereIsEmpty) {
  EXPECT_EQ(ProcFileField("/proc/meminfo", "NoSuchField"), "");
  EXPECT_EQ(ProcFileField("/nonexistent/meminfo", "MemTotal"), "");
}

}  // namespace
}  // namespace endorecon::base
