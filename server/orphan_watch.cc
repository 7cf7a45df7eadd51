#include "server/orphan_watch.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>
#include <utility>

#include "common/error.h"
#include "common/file_write.h"
#include "common/json_file.h"

namespace endorecon::server {

void OrphanWatch::KeepIn(const std::filesystem::path& file) {
  Read(file);
  file_ = file;
}

void OrphanWatch::ReadFrom(const std::filesystem::path& file) { Read(file); }

std::string OrphanWatch::Key(const std::filesystem::path& path) const {
  if (root_.empty()) return path.string();
  const auto relative = path.lexically_relative(root_);
  if (relative.empty() || *relative.begin() == "..") return path.string();
  return relative.generic_string();
}

void OrphanWatch::Read(const std::filesystem::path& file) {
  root_ = file.parent_path();
  std::error_code error;
  if (!std::filesystem::exists(file, error)) return;
  try {
    const nlohmann::json top = ReadJsonFile(file);
    if (!top.is_object() || !top.contains("orphans") || !top["orphans"].is_array())
      FailInvalid(file.string() + ": expected {\"orphans\": [{\"path\", \"found_unix_ms\"}, ...]}");
    std::map<std::string, std::int64_t> read;
    for (const auto& orphan : top["orphans"]) {
      const auto path = orphan.value("path", nlohmann::json());
      const auto found = orphan.value("found_unix_ms", nlohmann::json());
      // An entry that is no orphan (edited by hand) is left out: its file is found anew.
      if (path.is_string() && found.is_number_integer())
        read[path.get<std::string>()] = found.get<std::int64_t>();
    }
    found_ = std::move(read);
  } catch (const Error& e) {
    spdlog::warn(
        "{}; files no job references are counted from their next check (deleted later, never earlier)",
        e.what());
  }
}

void OrphanWatch::Sift(RetentionPlan& plan, const OrphanCutoff& cutoff, std::int64_t now_unix_ms) {
  std::map<std::string, std::int64_t> found;
  std::vector<BlobStore::StoredFile> due;
  plan.orphan_bytes = 0;
  plan.orphans_waiting = 0;
  const auto note = [&](const BlobStore::StoredFile& file) {
    const auto key = Key(file.path);
    const auto known = found_.find(key);
    return found[key] = known == found_.end() ? now_unix_ms : known->second;
  };
  for (const auto& file : plan.uploading) note(file);
  for (auto& file : plan.orphans) {
    const auto since = note(file);
    if (file.written < cutoff.written_before && since < cutoff.found_before_unix_ms) {
      // Forgotten now, as it is deleted next: kept, orphans.json listed it until the next check (an
      // hour by default; found 2026-12-07). One whose deletion fails is found anew: later, never earlier.
      found.erase(Key(file.path));
      plan.orphan_bytes += file.bytes;
      due.push_back(std::move(file));
    } else {
      ++plan.orphans_waiting;
    }
  }
  plan.orphans = std::move(due);
  const bool changed = found != found_;
  found_ = std::move(found);
  if (changed) Save();
}

void OrphanWatch::Save() const {
  if (file_.empty()) return;
  nlohmann::json orphans = nlohmann::json::array();
  for (const auto& [path, found] : found_) orphans.push_back({{"path", path}, {"found_unix_ms", found}});
  try {
    WriteFile(file_, nlohmann::json{{"orphans", orphans}}.dump(1) + "\n", "files no job references");
  } catch (const Error& e) {
    // In memory they hold; a restart finds them anew (later deletion, never earlier).
    spdlog::warn("{}", e.what());
  }
}

}  // namespace endorecon::server
