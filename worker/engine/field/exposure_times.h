// The exposure's knot times (exposure.h), checked apart from the module: a run's configuration
// (field_config.cc) checks them without the module's code.
#pragma once

#include <vector>

namespace endorecon::field {

// Throws Error(kInvalidArgument) naming the knot unless every time is finite and above the one before.
void CheckExposureTimes(const std::vector<float>& times);

}  // namespace endorecon::field
