#include "server/drain_file.h"

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/file_write.h"
#include "common/json_file.h"

namespace endorecon::server {

Drains ReadDrains(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) return {};
  const nlohmann::json top = ReadJsonFile(file);
  if (!top.is_object() || !top.contains("draining") || !top["draining"].is_object())
    FailInvalid(file.string() + ": expected {\"draining\": {\"WORKER\": LAST_SEEN_UNIX_MS, ...}}");
  Drains drains;
  for (const auto& [id, seen] : top["draining"].items()) {
    if (!seen.is_number_integer())
      FailInvalid(file.string() + ": worker '" + id + "': expected when it was last seen (Unix ms), found " +
                  seen.dump());
    drains[id] = seen.get<std::int64_t>();
  }
  return drains;
}

void WriteDrains(const std::filesystem::path& file, const Drains& drains) {
  nlohmann::json top = {{"draining", nlohmann::json::object()}};
  for (const auto& [id, seen] : drains) top["draining"][id] = seen;
  WriteFile(file, top.dump(1) + "\n", "drained workers");
}

}  // namespace endorecon::server
