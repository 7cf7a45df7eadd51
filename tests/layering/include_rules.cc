#include "tests/layering/include_rules.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <optional>
#include <regex>

namespace endorecon::layering {
namespace {

namespace fs = std::filesystem;

// The engine's layers by folder; the top-level files of worker/engine/ are the last layer.
const std::map<std::string, int>& EngineRanks() {
  static const std::map<std::string, int> ranks = {{"base", 0},  {"scene", 1}, {"field", 2}, {"render", 3},
                                                   {"train", 4}, {"eval", 4},  {"cuda", 5},  {"", 6}};
  return ranks;
}

bool StartsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

// The engine folder of a path under worker/engine/ ("" for its top-level files), or nothing.
std::optional<std::string> EngineFolder(const std::string& path) {
  const std::string prefix = "worker/engine/";
  if (!StartsWith(path, prefix)) return std::nullopt;
  const std::string rest = path.substr(prefix.size());
  const auto slash = rest.find('/');
  return slash == std::string::npos ? std::string() : rest.substr(0, slash);
}

std::string Named(const std::string& folder) {
  return folder.empty() ? "the engine's top level" : folder + "/";
}

// The rule `file` breaks by including `include`, or nothing.
std::optional<std::string> Broken(const std::string& file, const std::string& include) {
  const auto from = EngineFolder(file);
  if (from) {
    if (StartsWith(include, "grpc") || StartsWith(include, "server/") || StartsWith(include, "client/") ||
        StartsWith(include, "worker/runtime/") || StartsWith(include, "endorecon/v1/")) {
      return "the engine includes no gRPC and nothing of the service";
    }
    const auto to = EngineFolder(include);
    if (!to || *to == *from) return std::nullopt;
    const auto& ranks = EngineRanks();
    const auto rank_from = ranks.find(*from), rank_to = ranks.find(*to);
    if (rank_from == ranks.end() || rank_to == ranks.end()) {
      return "an engine folder outside the known layers (" + Named(rank_from == ranks.end() ? *from : *to) +
             ")";
    }
    if (rank_to->second >= rank_from->second) {
      return Named(*from) + " may not include " + Named(*to) +
             " (order: base, scene, field, render, train|eval, cuda, top level)";
    }
    return std::nullopt;
  }
  // The server checks a job's training configuration at submit through its one face (linking the
  // configuration's library, not the engine).
  if (StartsWith(file, "server/") && include == "worker/engine/train/config_check.h") return std::nullopt;
  if ((StartsWith(file, "client/") || StartsWith(file, "server/")) && StartsWith(include, "worker/")) {
    return "client/ and server/ never include the engine or the worker (the server: but for "
           "worker/engine/train/config_check.h)";
  }
  if (StartsWith(file, "common/") && !StartsWith(include, "common/") && !StartsWith(include, "endorecon/")) {
    return "common/ includes only common/ and the generated protocol";
  }
  return std::nullopt;
}

bool IsSource(const fs::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".h" || ext == ".cc" || ext == ".cu" || ext == ".cuh";
}

}  // namespace

std::vector<Violation> CheckIncludes(const fs::path& root) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*(["<])([^">]+)[">])");
  std::vector<std::string> files;
  for (const char* top : {"common", "server", "client", "worker"}) {
    if (!fs::is_directory(root / top)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
      if (entry.is_regular_file() && IsSource(entry.path())) {
        files.push_back(fs::relative(entry.path(), root).generic_string());
      }
    }
  }
  std::sort(files.begin(), files.end());
  std::vector<Violation> violations;
  for (const auto& file : files) {
    std::ifstream in(root / file);
    std::string text;
    int line = 0;
    while (std::getline(in, text)) {
      ++line;
      std::smatch match;
      if (!std::regex_search(text, match, kInclude)) continue;
      const std::string include = match[2].str();
      // System headers (<...>) are checked only for gRPC in the engine.
      if (match[1].str() == "<" && !(EngineFolder(file) && StartsWith(include, "grpc"))) continue;
      if (auto rule = Broken(file, include)) violations.push_back({file, line, include, *rule});
    }
  }
  return violations;
}

std::string Describe(const Violation& v) {
  return v.file + ":" + std::to_string(v.line) + " includes \"" + v.include + "\": " + v.rule;
}

}  // namespace endorecon::layering
