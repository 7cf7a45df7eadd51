// Reading the server's audit log (JSON Lines) in tests.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/unit/temp_dir.h"

namespace endorecon::testing {

// Every line of the audit log, parsed (a line that is not JSON fails the parse, and so the test).
inline std::vector<nlohmann::json> AuditLines(const std::filesystem::path& file) {
  std::vector<nlohmann::json> lines;
  std::istringstream text(ReadBytes(file));
  for (std::string line; std::getline(text, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

// The lines with this method and outcome (and principal and job, when given).
inline std::vector<nlohmann::json> AuditFind(const std::vector<nlohmann::json>& lines,
                                             const std::string& method, const std::string& outcome,
                                             const std::string& principal = "", const std::string& job = "") {
  std::vector<nlohmann::json> found;
  for (const auto& line : lines) {
    if (line.value("method", "") == method && line.value("outcome", "") == outcome &&
        (principal.empty() || line.value("principal", "") == principal) &&
        (job.empty() || line.value("job", "") == job)) {
      found.push_back(line);
    }
  }
  return found;
}

}  // namespace endorecon::testing
