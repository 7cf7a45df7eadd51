// The devices a worker serves, from its --devices flag: each runs one engine (one job at a time) with
// its own thread count.
#pragma once

#include <string>
#include <vector>

namespace endorecon::worker {

struct Device {
  std::string name;  // "cpu0", "gpu1", ...
  std::string kind;  // "cpu", or "cuda" once the CUDA engine exists
  int threads = 0;   // engine threads for a CPU slot
};

// "cpu" -> one CPU slot; "cpu:N" -> N CPU slots; "0,1,..." -> GPU indices (CUDA_VISIBLE_DEVICES
// style), which run as CPU slots until the CUDA engine exists. threads > 0: each slot's thread count;
// 0: the machine's `cores` shared evenly (at least 1 each). Throws Error(kInvalidArgument) naming the
// flag for any other form.
std::vector<Device> ParseDevices(const std::string& spec, int threads, int cores);

}  // namespace endorecon::worker
