// What a reader of a run's results must know before trusting them (a run that learnt nothing, a mesh
// with no triangle): logged as a warning and kept in metrics.json's "warnings", which the report page
// shows above its numbers and `endorecon status` under the job's outcome. These were in the worker's
// log alone, which a submitter never sees (found 2026-12-07).
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace endorecon::eval {

// Logs `text` as a warning and appends it to metrics["warnings"].
void Warn(nlohmann::json& metrics, const std::string& text);

}  // namespace endorecon::eval
