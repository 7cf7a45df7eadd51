#include "server/pacs_directory.h"

#include <algorithm>

#include "common/error.h"

namespace endorecon::server {

PacsDirectory::PacsDirectory(const std::vector<std::string>& flags) {
  for (const auto& flag : flags) {
    const auto equals = flag.find('=');
    if (equals == std::string::npos || equals == 0)
      FailInvalid("--pacs '" + flag + "': expected NAME=AET@HOST:PORT");
    const std::string name = flag.substr(0, equals);
    if (peers_.count(name)) FailInvalid("--pacs '" + flag + "': the name '" + name + "' is given twice");
    peers_[name] = dicom::ParsePeer(flag.substr(equals + 1));
  }
}

const dicom::Peer& PacsDirectory::Find(const std::string& name) const {
  const auto found = peers_.find(name);
  if (found == peers_.end()) {
    std::string known;
    for (const auto& [known_name, peer] : peers_) known += (known.empty() ? "" : ", ") + known_name;
    Fail(ErrorCode::kNotFound,
         "no PACS named '" + name + "' is configured on the server (" +
             (known.empty() ? std::string("none is; start it with --pacs NAME=AET@HOST:PORT")
                            : "known: " + known) +
             ")");
  }
  return found->second;
}

std::vector<std::string> PacsDirectory::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, peer] : peers_) names.push_back(name);
  return names;
}

std::int64_t RetryWaitMs(int first_ms, int attempt) {
  return std::min<std::int64_t>(60000, static_cast<std::int64_t>(first_ms) << std::clamp(attempt - 1, 0, 20));
}

}  // namespace endorecon::server
