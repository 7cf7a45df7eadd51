// Checkpoints as a resuming worker reads them (train::ReadCheckpointConfig, then ReadCheckpointState
// into a trainer of the tiny run's shape); inputs per tests/fuzz/sealed_input.h. A checkpoint that
// is refused is refused as corrupt or as no checkpoint, naming the file.
#include <memory>

#include "tests/fuzz/fuzz_input.h"
#include "tests/fuzz/sealed_input.h"
#include "tests/fuzz/tiny_run.h"
#include "worker/engine/train/checkpoint.h"

namespace {

using namespace endorecon;

train::Trainer& TinyTrainer() {
  static const scene::Clip clip = fuzz::TinyClip(fuzz::ScratchDir() / "tiny_clip");
  static train::Trainer trainer(clip, fuzz::TinyConfig(), {0, 1}, 1);
  return trainer;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto& trainer = TinyTrainer();
  const auto path = fuzz::WriteInput("checkpoint.bin", fuzz::SealedFileOf(data, size));
  const std::initializer_list<ErrorCode> refusals = {ErrorCode::kInvalidArgument, ErrorCode::kDataLoss};
  fuzz::Accepts([&] { train::ReadCheckpointConfig(path); }, refusals, path.string());
  fuzz::Accepts([&] { train::ReadCheckpointState(path, trainer); }, refusals, path.string());
  return 0;
}
