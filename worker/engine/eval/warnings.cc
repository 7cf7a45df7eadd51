#include "worker/engine/eval/warnings.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

namespace endorecon::eval {

void Warn(nlohmann::json& metrics, const std::string& text) {
  spdlog::warn("{}", text);
  metrics["warnings"].push_back(text);
}

}  // namespace endorecon::eval
