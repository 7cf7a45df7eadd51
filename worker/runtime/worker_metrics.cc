#include "worker/runtime/worker_metrics.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "common/error.h"
#include "common/metrics_exposer.h"

namespace endorecon::worker {

using prometheus::BuildCounter;
using prometheus::BuildGauge;

WorkerMetrics::WorkerMetrics(const std::string& bind_address, const std::vector<Device>& devices)
    : registry_(std::make_shared<prometheus::Registry>()),
      memory_(BuildGauge()
                  .Name("endorecon_worker_memory_bytes")
                  .Help("Resident memory of the worker process")
                  .Register(*registry_)
                  .Add({})) {
  auto& samples = BuildGauge()
                      .Name("endorecon_worker_samples_per_second")
                      .Help("Training samples per second")
                      .Register(*registry_);
  auto& iterations = BuildCounter()
                         .Name("endorecon_worker_iterations_total")
                         .Help("Training iterations done")
                         .Register(*registry_);
  auto& psnr = BuildGauge()
                   .Name("endorecon_worker_psnr_db")
                   .Help("Training PSNR of the running job")
                   .Register(*registry_);
  auto& busy =
      BuildGauge().Name("endorecon_worker_busy").Help("1 while the device runs a job").Register(*registry_);
  auto& info =
      BuildGauge().Name("endorecon_worker_device_info").Help("The worker's devices").Register(*registry_);
  for (const auto& device : devices) {
    const prometheus::Labels labels{{"device", device.name}};
    devices_.emplace_back(device.name, DeviceGauges{samples.Add(labels), iterations.Add(labels),
                                                    psnr.Add(labels), busy.Add(labels)});
    info.Add({{"device", device.name}, {"kind", device.kind}}).Set(1);
  }
  AddGpuGauges(devices);
  UpdateMemory();
  if (!bind_address.empty()) {
    exposer_ = OpenMetricsExposer(bind_address);
    exposer_->RegisterCollectable(registry_);
  }
}

void WorkerMetrics::AddGpuGauges(const std::vector<Device>& devices) {
  const bool any_gpu =
      std::any_of(devices.begin(), devices.end(), [](const Device& d) { return d.kind == "cuda"; });
  if (!any_gpu) return;
  std::string problem;
  gpu_monitor_ = GpuMonitor::Open(problem);
  if (!gpu_monitor_) {
    spdlog::warn("no GPU memory or utilisation metrics: {}", problem);
    return;
  }
  auto& used = BuildGauge()
                   .Name("endorecon_worker_gpu_memory_used_bytes")
                   .Help("GPU memory in use (every process on the GPU)")
                   .Register(*registry_);
  auto& total =
      BuildGauge().Name("endorecon_worker_gpu_memory_total_bytes").Help("GPU memory").Register(*registry_);
  auto& utilization = BuildGauge()
                          .Name("endorecon_worker_gpu_utilization")
                          .Help("Share of the last sample period a kernel ran on the GPU (NVML)")
                          .Register(*registry_);
  for (const auto& device : devices) {
    if (device.kind != "cuda") continue;
    const prometheus::Labels labels{{"device", device.name}};
    gpus_.push_back(
        {device.description.pci_bus_id, used.Add(labels), total.Add(labels), utilization.Add(labels)});
  }
}

int WorkerMetrics::port() const { return exposer_ ? exposer_->GetListeningPorts().at(0) : 0; }

WorkerMetrics::DeviceGauges& WorkerMetrics::For(const std::string& device) {
  for (auto& [name, gauges] : devices_) {
    if (name == device) return gauges;
  }
  Fail(ErrorCode::kInternal, "no metrics for device " + device);
}

void WorkerMetrics::UpdateMemory() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  memory_.Set(static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)));
  for (auto& gpu : gpus_) {
    if (const auto reading = gpu_monitor_->Read(gpu.pci_bus_id)) {
      gpu.used.Set(reading->memory_used_bytes);
      gpu.total.Set(reading->memory_total_bytes);
      gpu.utilization.Set(reading->utilization);
    }
  }
}

}  // namespace endorecon::worker
