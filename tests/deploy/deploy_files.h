// What the deploy tests share: the repository's files, and the flags a built binary accepts.
#pragma once

#include <filesystem>
#include <memory>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {

inline std::filesystem::path SourcePath(const std::string& relative) {
  return std::filesystem::path(ENDORECON_SOURCE_DIR) / relative;
}

// A cluster (admin credentials) whose every metric series exists: a PACS destination named (nothing
// listens there) for the per-PACS series, and worker "w1" started with a token that expires, for
// the token expiry's series.
inline std::unique_ptr<Cluster> ClusterOfEverySeries() {
  auto cluster =
      std::make_unique<Cluster>(std::vector<std::string>{"--pacs", "pacs1=PACS1@127.0.0.1:1"}, false);
  cluster->UseCredentials(MakeCredentials(*cluster, "", "admin", "", "ops"));
  const auto token =
      WriteTokenFile(cluster->path("worker.token"),
                     CreateToken(cluster->data_dir(), "worker", "", "w1", {"--expires-in", "30d"}));
  cluster->StartServer();
  cluster->StartWorker("w1", {"--token-file", token.string()});
  return cluster;
}

// The built binary that `name` (endorecon-server, endorecon-worker, endorecon) is.
inline std::string BinaryNamed(const std::string& name) {
  if (name == "endorecon-server") return BuiltBinary("server/endorecon-server");
  if (name == "endorecon-worker") return BuiltBinary("worker/runtime/endorecon-worker");
  if (name == "endorecon") return BuiltBinary("client/endorecon");
  return "";
}

// The long options (--name) that `binary [subcommand] --help` lists.
inline std::set<std::string> AcceptedFlags(const std::string& binary, const std::string& subcommand = "") {
  TempDir scratch("help");
  std::vector<std::string> argv{binary};
  if (!subcommand.empty()) argv.push_back(subcommand);
  argv.push_back("--help");
  Process(argv, scratch / "help").Wait();
  const std::string help = ReadBytes(scratch / "help");
  std::set<std::string> flags;
  const std::regex flag("--[a-z][a-z0-9-]*");
  for (auto it = std::sregex_iterator(help.begin(), help.end(), flag); it != std::sregex_iterator(); ++it)
    flags.insert(it->str());
  return flags;
}

// Every endorecon_* metric name in `text`.
inline std::set<std::string> MetricNames(const std::string& text) {
  std::set<std::string> names;
  const std::regex name("endorecon_[a-z_]+");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), name); it != std::sregex_iterator(); ++it)
    names.insert(it->str());
  return names;
}

}  // namespace endorecon::testing
