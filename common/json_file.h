// Small JSON side files of the clip layouts (transforms.json, stereo.json).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace endorecon {

// Parses the file; throws FailInvalid naming it when it cannot be read or is not valid JSON.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace endorecon
