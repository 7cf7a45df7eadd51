// The audit log: JSON Lines, one line per mutating call and per refused call, for an auditor to
// read who did what. Each line: time (UTC, ISO 8601 with milliseconds), principal (the token's
// label), role, tenant, method, job (id, when the call concerns one), outcome ("OK" or the gRPC
// status name), peer (the caller's address) and, for a caller with a client certificate, its
// subject's common name; for token changes, the subject (the token's label); for a paced refusal,
// held_back (server/refusal_pacer.h). Never a token, a message text, a
// file name or a job name: those may carry patient data.
//
// Appends with O_APPEND and one write per line, so the server and `endorecon-server token ...`
// may write the same file at once. Lines reach the kernel before the call returns; they are not
// fsynced, so refused calls cannot be turned into a stream of disk flushes. Thread-safe.
#pragma once

#include <filesystem>
#include <functional>
#include <mutex>
#include <string>

namespace endorecon::server {

struct AuditEntry {
  std::string principal;
  std::string role;
  std::string tenant;
  std::string method;
  std::string job_id;
  std::string outcome;
  std::string peer;
  std::string certificate;
  std::string subject;
  long long held_back = 0;  // refusals alike not written since the kind's last line (RefusalPacer)
};

class AuditLog {
 public:
  // Opens `file` for appending (created with mode 0640). Throws Error(kUnavailable) naming it.
  explicit AuditLog(const std::filesystem::path& file);
  ~AuditLog();
  AuditLog(const AuditLog&) = delete;
  AuditLog& operator=(const AuditLog&) = delete;

  // Writes one line with the current time. A failed write is logged (spdlog) and not thrown: the
  // call it describes has already happened. It is counted (SetFailureObserver) for an alert: lines
  // lost to a full disk were only logged (found 2026-12-07).
  void Write(const AuditEntry& entry);
  // Called once per failed write; set before the log is shared between threads.
  void SetFailureObserver(std::function<void()> observer) { on_failure_ = std::move(observer); }

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::mutex mutex_;
  std::function<void()> on_failure_;
};

}  // namespace endorecon::server
