// A field's parameters as bytes: an exact binary copy of every parameter block, named, for checkpoints
// and models. The format: magic "ENDORECON-FIELD\0", a version, the scalar size and the block count,
// then per block its name, its size and its values.
#pragma once

#include <iosfwd>

#include "worker/engine/field/field.h"

namespace endorecon::field {

template <typename S>
void SaveFieldState(const FieldT<S>& field, std::ostream& out);

// Throws Error(kDataLoss) for a stream that is not a field state, a truncated one, or one written by a
// field of another shape (the message says which block differs); the field is then unusable (partly
// overwritten) and must not be trained or rendered.
template <typename S>
void LoadFieldState(FieldT<S>& field, std::istream& in);

}  // namespace endorecon::field
