#include "worker/engine/field/exposure_times.h"

#include <cmath>
#include <cstddef>
#include <string>

#include "common/error.h"

namespace endorecon::field {

void CheckExposureTimes(const std::vector<float>& times) {
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (!std::isfinite(times[k]) || (k > 0 && !(times[k] > times[k - 1]))) {
      FailInvalid("field.exposure_times must be finite and ascending; knot " + std::to_string(k) + " is " +
                  std::to_string(times[k]));
    }
  }
}

}  // namespace endorecon::field
