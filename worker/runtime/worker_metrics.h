// The worker's Prometheus metrics (prometheus-cpp), served at http://<bind>/metrics.
//   endorecon_worker_samples_per_second{device}  gauge: training samples (ray points) per second
//   endorecon_worker_iterations_total{device}    counter: training iterations done
//   endorecon_worker_psnr_db{device}             gauge: current training PSNR of the running job
//   endorecon_worker_busy{device}                gauge: 1 while the device runs a job
//   endorecon_worker_memory_bytes                gauge: resident memory of the worker process
//   endorecon_worker_device_info{device,kind}    gauge, always 1: the devices and what they are
#pragma once

#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/registry.h>

#include <memory>
#include <string>
#include <vector>

#include "worker/runtime/device_list.h"

namespace endorecon::worker {

class WorkerMetrics {
 public:
  // Serves on `bind_address` ("127.0.0.1:9465"; port 0 picks one); empty: not served.
  WorkerMetrics(const std::string& bind_address, const std::vector<Device>& devices);
  int port() const;

  // One device's view of the running job.
  struct DeviceGauges {
    prometheus::Gauge& samples_per_second;
    prometheus::Counter& iterations;
    prometheus::Gauge& psnr;
    prometheus::Gauge& busy;
  };
  DeviceGauges& For(const std::string& device);
  // Refreshes the memory gauge from /proc/self/statm.
  void UpdateMemory();

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  prometheus::Gauge& memory_;
  std::vector<std::pair<std::string, DeviceGauges>> devices_;
};

}  // namespace endorecon::worker
