// Which worker holds which running job, until when. A lease not renewed before its expiry is
// taken back by the caller of TakeExpired (the job goes back to the queue). In memory; after a
// restart the server re-grants the leases of RUNNING jobs with a fresh expiry, so live workers
// carry on. Thread-safe; the clock is passed in so tests control time.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace endorecon::server {

using Clock = std::chrono::steady_clock;

// The token a lease's worker last called with. When it expires the worker's calls are refused and
// the lease cannot be renewed: the job was lost to the credential, not to the job or the worker.
struct LeaseToken {
  std::string name;                  // its label
  std::int64_t expires_unix_ms = 0;  // 0: never (or no token store)
};

struct Lease {
  std::string id;
  std::string job_id;
  std::string worker_id;
  Clock::time_point expiry;
  LeaseToken token;
  // Re-created at the server's start (Restore) and not renewed since: its worker has not called
  // this server, and may have handed the job back while it was down.
  bool restored = false;
};

class LeaseTable {
 public:
  explicit LeaseTable(Clock::duration ttl) : ttl_(ttl) {}

  // Grants a new lease (a fresh random id) on `job_id` to `worker_id`, expiring ttl after `now`.
  Lease Grant(const std::string& job_id, const std::string& worker_id, Clock::time_point now,
              LeaseToken token = {});
  // Re-creates a lease known from the job store under its old id (restored until renewed).
  void Restore(const std::string& lease_id, const std::string& job_id, const std::string& worker_id,
               Clock::time_point now);
  // Extends a lease to ttl after `now`, noting the `token` the renewing call carried (the worker's
  // token may have been replaced); nullopt if it is unknown or already expired.
  std::optional<Lease> Renew(const std::string& lease_id, Clock::time_point now,
                             const LeaseToken& token = {});
  std::optional<Lease> Find(const std::string& lease_id) const;
  // Ends a lease; false if it was not held.
  bool Release(const std::string& lease_id);
  // Removes and returns every lease whose expiry is at or before `now`.
  std::vector<Lease> TakeExpired(Clock::time_point now);
  std::vector<Lease> All() const;
  Clock::duration ttl() const { return ttl_; }

 private:
  Clock::duration ttl_;
  mutable std::mutex mutex_;
  std::map<std::string, Lease> leases_;
};

// A random identifier of `bytes` random bytes, as lowercase hex (OpenSSL RAND_bytes).
std::string RandomId(int bytes);

}  // namespace endorecon::server
