// Small JSON files and texts: the clip layouts' side files (transforms.json, stereo.json), a run's
// --config, a job's configuration.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace endorecon {

// No JSON here nests deeper: a file of 60,000 nested arrays (120 kB) crashed a recursive walk of it.
inline constexpr int kMostJsonDepth = 64;

// Parses `text`; throws FailInvalid naming `what` when it is not valid JSON or nests deeper than
// kMostJsonDepth.
nlohmann::json ParseJson(std::string_view text, const std::string& what);

// Parses the file; throws FailInvalid naming it when it cannot be read, is not a regular file, or
// ParseJson refuses it.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace endorecon
