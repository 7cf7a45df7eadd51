// The one face of the training configuration the service uses: the server checks a job's --config
// with it at submit (keys, types and bounds, as the engine takes them) and links only the
// configuration's library (endorecon_train_config), not the engine.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace endorecon::train {

// Throws Error(kInvalidArgument) naming the key unless `config` (config.json's "train" object, or a
// part of it) applies over the named preset ("cpu", "gpu" or "paper") as a run would apply it.
void CheckConfigJson(const nlohmann::json& config, const std::string& preset);

}  // namespace endorecon::train
