#include "common/metrics_exposer.h"

#include <gtest/gtest.h>

#include "tests/unit/clip_fixture.h"

namespace endorecon {
namespace {

// An IPv6 --metrics-host is bracketed ("::" made ":::9465"); a taken port is named with its flags.
TEST(MetricsExposerTest, AnAddressIsHostAndPortAndATakenPortSaysSo) {
  EXPECT_EQ(MetricsAddress("127.0.0.1", 9465), "127.0.0.1:9465");
  EXPECT_EQ(MetricsAddress("::", 9465), "[::]:9465");
  EXPECT_EQ(MetricsAddress("[::1]", 9465), "[::1]:9465");
  const auto taken = OpenMetricsExposer("127.0.0.1:0");
  const auto port = taken->GetListeningPorts().at(0);
  const auto message = testing::ErrorFrom([&] { OpenMetricsExposer(MetricsAddress("127.0.0.1", port)); },
                                          ErrorCode::kUnavailable);
  EXPECT_NE(message.find("--metrics-host, --metrics-port): the port is taken"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon
