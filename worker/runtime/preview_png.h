// Engine previews (raw 8-bit pixels) become small PNGs for the wire.
#pragma once

#include "endorecon/v1/job.pb.h"
#include "worker/engine/eval/preview.h"

namespace endorecon::worker {

// Encodes `preview` as PNG (RGB or grey); `iteration` is the training iteration it shows.
v1::Preview EncodePreview(const eval::Preview& preview, int iteration);

}  // namespace endorecon::worker
