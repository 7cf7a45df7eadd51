// Trained models as `endorecon-worker render` reads them (train::ReadModel); inputs per
// tests/fuzz/sealed_input.h. An accepted model has a field built from the file's configuration, a
// finite scene box with min < max and finite bounds with 0 <= near < far; a refused one is refused as corrupt
// or as no model, naming the file.
#include <cmath>

#include "tests/fuzz/fuzz_input.h"
#include "tests/fuzz/sealed_input.h"
#include "worker/engine/train/checkpoint.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto path = fuzz::WriteInput("model.bin", fuzz::SealedFileOf(data, size));
  train::Model model;
  if (!fuzz::Accepts([&] { model = train::ReadModel(path); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kDataLoss}, path.string())) {
    return 0;
  }
  if (!model.field) fuzz::Broken("accepted a model without a field");
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(model.box.min[k]) || !std::isfinite(model.box.max[k]) ||
        !(model.box.min[k] < model.box.max[k]))
      fuzz::Broken("accepted a scene box that is not finite with min < max");
  }
  if (!std::isfinite(model.near) || !std::isfinite(model.far) || !(model.near >= 0 && model.near < model.far))
    fuzz::Broken("accepted bounds that are not finite with 0 <= near < far");
  return 0;
}
