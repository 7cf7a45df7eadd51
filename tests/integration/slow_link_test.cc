// A client on a slow link: when the connection's handshake takes longer than a loopback one (a far
// site, TLS, a loaded server), calls wait for it inside their deadline instead of failing at once.
#include <gtest/gtest.h>

#include <string>

#include "tests/integration/delaying_proxy.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

int PortOf(const std::string& address) { return std::stoi(address.substr(address.rfind(':') + 1)); }

TEST(SlowLinkTest, ACallWhoseConnectionTakesSecondsToOpenStillSucceeds) {
  Cluster cluster;
  // gRPC gives a connection attempt max(min_reconnect_backoff, backoff) to open: endorecon set that
  // to 200 ms, so every CLI call over a link slower than that failed UNAVAILABLE ("connection
  // attempt timed out before receiving SETTINGS frame"; found by the TSan run, where the server is
  // that slow). 2.5 s: longer than the longest backoff (2 s) too.
  DelayingProxy proxy(PortOf(cluster.address()), std::chrono::milliseconds(2500));
  const auto listed = RunCli("127.0.0.1:" + std::to_string(proxy.port()), {"list"});
  EXPECT_EQ(listed.exit_code, 0) << listed.err;
}

}  // namespace
}  // namespace endorecon::testing
