#include "common/json_file.h"

#include <fstream>
#include <iterator>

#include "common/error.h"
#include "common/file_read.h"

namespace endorecon {

nlohmann::json ParseJson(std::string_view text, const std::string& what) {
  const auto depth_check = [&](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
    if (depth >= kMostJsonDepth)  // depth counts from 0 at the top level
      FailInvalid(what + ": nested deeper than " + std::to_string(kMostJsonDepth) + " levels");
    return true;
  };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), depth_check);
  } catch (const nlohmann::json::exception& e) {
    FailInvalid(what + ": not valid JSON (" + e.what() + ")");
  }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  std::ifstream in = OpenToRead(path);  // no FIFO (its read would wait for ever): RequireRegularFile
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ParseJson(text, path.string());
}

}  // namespace endorecon
