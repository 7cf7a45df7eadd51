// A run's configuration JSON (`--config FILE`, a job's config_json) applied over the CPU preset with
// train::ApplyJson. Whatever it accepts must survive its own round trip: ToJson, then ApplyJson over
// a fresh preset, gives the same configuration.
#include <nlohmann/json.hpp>

#include "tests/fuzz/fuzz_input.h"
#include "worker/engine/train/train_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  // Text that is not JSON never reaches ApplyJson: the worker and the CLI refuse it while parsing.
  const auto json = nlohmann::json::parse(fuzz::Bytes(data, size), nullptr, false);
  if (json.is_discarded()) return 0;
  auto config = train::TrainConfig::Preset("cpu");
  if (!fuzz::Accepts([&] { train::ApplyJson(json, config); }, {ErrorCode::kInvalidArgument}, "config"))
    return 0;
  const nlohmann::json written = train::ToJson(config);
  auto again = train::TrainConfig::Preset("cpu");
  if (!fuzz::Accepts([&] { train::ApplyJson(written, again); }, {})) return 0;
  if (train::ToJson(again) != written) fuzz::Broken("the accepted configuration does not round-trip");
  return 0;
}
