#include "server/refusal_pacer.h"

namespace endorecon::server {
namespace {

// "ipv4:10.1.2.3:51234" -> "ipv4:10.1.2.3": each connection has a port of its own.
std::string Address(const std::string& peer) {
  const auto colon = peer.rfind(':');
  return colon == std::string::npos ? peer : peer.substr(0, colon);
}

}  // namespace

bool RefusalPacer::Pass(AuditEntry& entry, Clock::time_point now) {
  const std::string key =
      entry.principal + '\n' + Address(entry.peer) + '\n' + entry.method + '\n' + entry.outcome;
  std::lock_guard lock(mutex_);
  auto found = kinds_.find(key);
  if (found == kinds_.end()) {
    if (kinds_.size() < kMostKinds) kinds_.emplace(key, Kind{now, 1, 0, {}});
    return true;
  }
  Kind& kind = found->second;
  if (now - kind.window_start >= window_) {
    entry.held_back = kind.held;
    kind = Kind{now, 1, 0, {}};
    return true;
  }
  if (kind.lines < burst_) {
    ++kind.lines;
    return true;
  }
  kind.latest = entry;
  ++kind.held;
  return false;
}

std::vector<AuditEntry> RefusalPacer::TakeDue(Clock::time_point now) {
  std::vector<AuditEntry> due;
  std::lock_guard lock(mutex_);
  for (auto it = kinds_.begin(); it != kinds_.end();) {
    Kind& kind = it->second;
    if (now - kind.window_start < window_) {
      ++it;
    } else if (kind.held > 0) {
      AuditEntry line = kind.latest;
      line.held_back = kind.held - 1;  // the line is one of them
      due.push_back(std::move(line));
      kind = Kind{now, 1, 0, {}};
      ++it;
    } else {
      it = kinds_.erase(it);  // a window without a refusal held back: forgotten
    }
  }
  return due;
}

}  // namespace endorecon::server
