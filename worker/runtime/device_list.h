// The devices a worker serves, from its --devices flag: each runs one engine (one job at a time) with
// its own thread count.
#pragma once

#include <string>
#include <vector>

#include "worker/engine/device_description.h"

namespace endorecon::worker {

struct Device {
  std::string name;  // "cpu0", "gpu1", ...
  std::string kind;  // "cpu" or "cuda"
  int threads = 0;   // host threads of the engine (a CPU slot's training; a GPU's periodic rounds)
  int index = -1;    // the CUDA device index of a "cuda" device
  DeviceDescription description;  // what it is (DescribeDevices)

  // The engine's device name: "cpu" or "cuda:N" (ReconstructOptions::device).
  std::string EngineDevice() const { return kind == "cuda" ? "cuda:" + std::to_string(index) : "cpu"; }
};

// "cpu" -> one CPU slot; "cpu:N" -> N CPU slots; "0,1,..." -> CUDA device indices (as
// CUDA_VISIBLE_DEVICES leaves them), one engine each. threads > 0: each device's host thread count;
// 0: the machine's `cores` shared evenly (at least 1 each). Throws Error(kInvalidArgument) naming the
// flag for any other form. Whether the GPUs exist is DescribeDevices' business.
std::vector<Device> ParseDevices(const std::string& spec, int threads, int cores);

// Fills each device's description (its model and memory). Refuses, naming the device and the reason,
// a GPU this build or machine cannot run (a build without CUDA, an index past the last device):
// never a silent fallback to the CPU.
void DescribeDevices(std::vector<Device>& devices);

}  // namespace endorecon::worker
