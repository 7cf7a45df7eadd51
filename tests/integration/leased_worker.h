// A worker of the test's own process: registered with one CPU device, it leases the cluster's next
// job, and the test calls the runner (worker::RunLeasedJob) itself, to stall or race it at will.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "tests/integration/service_harness.h"
#include "worker/runtime/worker_client.h"

namespace endorecon::testing {

struct LeasedWorker {
  worker::Device device;
  std::unique_ptr<worker::WorkerClient> client;
  std::optional<v1::LeaseResponse> lease;  // none when no job came within 10 s
};

inline LeasedWorker LeaseAsWorker(const Cluster& cluster, const std::string& worker_id) {
  LeasedWorker leased;
  leased.device.name = "cpu0";
  leased.device.kind = "cpu";
  leased.device.threads = 1;
  leased.client =
      std::make_unique<worker::WorkerClient>(cluster.address(), ChannelSecurity{}, worker_id, std::chrono::seconds(10));
  leased.client->Register("localhost", {leased.device});
  leased.lease = leased.client->Lease(leased.device.name, std::chrono::seconds(10));
  return leased;
}

}  // namespace endorecon::testing
