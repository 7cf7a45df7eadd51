// What a field was built from, for people: the encoder (grids with their levels, and what was left out
// above the resolution cap), the blend, the deformation (or that it was left out), the heads and the
// parameter count of each block. Logged at the start of a run and written to metrics.json.
#pragma once

#include <string>

#include "worker/engine/field/field.h"

namespace endorecon::field {

template <typename S>
std::string DescribeField(const FieldT<S>& field);

}  // namespace endorecon::field
