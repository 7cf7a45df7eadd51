// The worker's Prometheus metrics (prometheus-cpp), served at http://<bind>/metrics.
//   endorecon_worker_samples_per_second{device}  gauge: training samples (ray points) per second
//   endorecon_worker_iterations_total{device}    counter: training iterations done
//   endorecon_worker_psnr_db{device}             gauge: current training PSNR of the running job
//   endorecon_worker_busy{device}                gauge: 1 while the device runs a job
//   endorecon_worker_memory_bytes                gauge: resident memory of the worker process
//   endorecon_worker_device_info{device,kind}    gauge, always 1: the devices and what they are
//   endorecon_worker_gpu_memory_used_bytes{device}, endorecon_worker_gpu_memory_total_bytes{device},
//   endorecon_worker_gpu_utilization{device}     gauges of each GPU (0..1: the share of time a kernel
//                                                ran), read through NVML where the driver has it
#pragma once

#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/registry.h>

#include <memory>
#include <string>
#include <vector>

#include "worker/runtime/device_list.h"
#include "worker/runtime/gpu_monitor.h"

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
  // Refreshes the memory gauge from /proc/self/statm and the GPUs' gauges from NVML.
  void UpdateMemory();

 private:
  void AddGpuGauges(const std::vector<Device>& devices);
  std::shared_ptr<prometheus::Registry> registry_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  prometheus::Gauge& memory_;
  std::vector<std::pair<std::string, DeviceGauges>> devices_;
  struct GpuGauges {
    std::string pci_bus_id;
    prometheus::Gauge& used;
    prometheus::Gauge& total;
    prometheus::Gauge& utilization;
  };
  std::unique_ptr<GpuMonitor> gpu_monitor_;  // null without GPUs or without NVML
  std::vector<GpuGauges> gpus_;
};

}  // namespace endorecon::worker
