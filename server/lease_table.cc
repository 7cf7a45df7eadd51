#include "server/lease_table.h"

#include <openssl/rand.h>

#include <utility>
#include <vector>

#include "common/error.h"

namespace endorecon::server {

std::string RandomId(int bytes) {
  std::vector<unsigned char> raw(static_cast<std::size_t>(bytes));
  if (RAND_bytes(raw.data(), bytes) != 1) Fail(ErrorCode::kInternal, "RAND_bytes failed");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id;
  for (const unsigned char byte : raw) {
    id.push_back(kHex[byte >> 4]);
    id.push_back(kHex[byte & 15]);
  }
  return id;
}

Lease LeaseTable::Grant(const std::string& job_id, const std::string& worker_id, Clock::time_point now,
                        LeaseToken token) {
  Lease lease{RandomId(12), job_id, worker_id, now + ttl_, std::move(token)};
  std::lock_guard lock(mutex_);
  leases_[lease.id] = lease;
  return lease;
}

void LeaseTable::Restore(const std::string& lease_id, const std::string& job_id, const std::string& worker_id,
                         Clock::time_point now) {
  std::lock_guard lock(mutex_);
  leases_[lease_id] = Lease{lease_id, job_id, worker_id, now + ttl_, {}, true};
}

std::optional<Lease> LeaseTable::Renew(const std::string& lease_id, Clock::time_point now,
                                       const LeaseToken& token) {
  std::lock_guard lock(mutex_);
  const auto found = leases_.find(lease_id);
  if (found == leases_.end() || found->second.expiry <= now) return std::nullopt;
  found->second.expiry = now + ttl_;
  found->second.token = token;
  found->second.restored = false;
  return found->second;
}

std::optional<Lease> LeaseTable::Find(const std::string& lease_id) const {
  std::lock_guard lock(mutex_);
  const auto found = leases_.find(lease_id);
  if (found == leases_.end()) return std::nullopt;
  return found->second;
}

bool LeaseTable::Release(const std::string& lease_id) {
  std::lock_guard lock(mutex_);
  return leases_.erase(lease_id) > 0;
}

std::vector<Lease> LeaseTable::TakeExpired(Clock::time_point now) {
  std::lock_guard lock(mutex_);
  std::vector<Lease> expired;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.expiry <= now) {
      expired.push_back(it->second);
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  return expired;
}

std::vector<Lease> LeaseTable::All() const {
  std::lock_guard lock(mutex_);
  std::vector<Lease> all;
  for (const auto& [id, lease] : leases_) all.push_back(lease);
  return all;
}

}  // namespace endorecon::server
