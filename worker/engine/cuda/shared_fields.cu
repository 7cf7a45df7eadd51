#include "worker/engine/cuda/shared_fields.h"

namespace endorecon::cuda {

std::shared_ptr<DeviceField> SharedFields::For(field::Field& host) {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::weak_ptr<DeviceField>& slot = fields_[&host];
  std::shared_ptr<DeviceField> field = slot.lock();
  if (!field) {
    field = std::make_shared<DeviceField>(host);
    slot = field;
  }
  return field;
}

std::shared_ptr<DeviceField> DeviceFieldFor(SharedFields* shared, field::Field& host) {
  return shared != nullptr ? shared->For(host) : std::make_shared<DeviceField>(host);
}

}  // namespace endorecon::cuda
