// The device copies of host fields on one GPU, shared by the backends of one run: the training step
// and every renderer of the same host field use one DeviceField, so renders read the parameters the
// steps wrote, with no copy either way (the step backend's PullField and PushField move them between
// the host field and that copy). A plain C++ header; defined in shared_fields.cu (builds with
// ENDORECON_WITH_CUDA only).
#pragma once

#include <map>
#include <memory>
#include <mutex>

#include "worker/engine/cuda/device_field.h"

namespace endorecon::cuda {

class SharedFields {
 public:
  // The device copy of `host`: the one another backend already uses, or a new one (uploaded from the
  // host field now) on the calling thread's current device. It lives as long as a backend holds it.
  std::shared_ptr<DeviceField> For(field::Field& host);

 private:
  std::mutex mutex_;
  std::map<const field::Field*, std::weak_ptr<DeviceField>> fields_;
};

// What a backend runs on: shared->For(host), or a device copy of its own when `shared` is null.
std::shared_ptr<DeviceField> DeviceFieldFor(SharedFields* shared, field::Field& host);

}  // namespace endorecon::cuda
