#include "server/audit_log.h"

#include <fcntl.h>
#include <fmt/chrono.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "server/access_failure.h"

namespace endorecon::server {
namespace {

std::string UtcNow() {
  const auto now = std::chrono::system_clock::now();
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03}Z", fmt::gmtime(std::chrono::system_clock::to_time_t(now)),
                     ms);
}

}  // namespace

AuditLog::AuditLog(const std::filesystem::path& file) : path_(file) {
  // Non-blocking to open: a named pipe without a reader held the server in open() at start, deaf to
  // SIGTERM (found 2026-12-06); one with a reader (a log shipper) is taken. Writes block as before.
  fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NONBLOCK, 0640);
  if (fd_ < 0 && errno == ENXIO) {
    Fail(ErrorCode::kInvalidArgument,
         "--audit-log " + file.string() +
             ": a named pipe (FIFO) that no process reads: start its reader first, "
             "or name a file");
  }
  // A mistyped path is the operator's to fix (exit 2, as a missing --quotas), not the disk's (found
  // 2026-12-07: exit 1, "UNAVAILABLE").
  const int error = errno;
  std::error_code ignored;
  const std::filesystem::path folder = file.parent_path().empty() ? "." : file.parent_path();
  if (fd_ < 0 && error == ENOENT && !std::filesystem::exists(folder, ignored)) {
    Fail(ErrorCode::kNotFound,
         "--audit-log " + file.string() + ": its folder " + folder.string() + " does not exist");
  }
  if (fd_ < 0 && error == ENOTDIR) {
    Fail(ErrorCode::kInvalidArgument,
         "--audit-log " + file.string() + ": " + folder.string() + " is a file, not a folder");
  }
  if (fd_ < 0 && error == EISDIR) {
    Fail(ErrorCode::kInvalidArgument, "--audit-log " + file.string() + ": a folder; name a file in it");
  }
  if (fd_ < 0) FailAccess("cannot open audit log " + file.string(), error);
  ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
}

AuditLog::~AuditLog() { ::close(fd_); }

void AuditLog::Write(const AuditEntry& entry) {
  nlohmann::ordered_json line{{"time", UtcNow()},         {"principal", entry.principal},
                              {"role", entry.role},       {"tenant", entry.tenant},
                              {"method", entry.method},   {"job", entry.job_id},
                              {"outcome", entry.outcome}, {"peer", entry.peer}};
  if (!entry.certificate.empty()) line["certificate"] = entry.certificate;
  if (!entry.subject.empty()) line["subject"] = entry.subject;
  if (entry.held_back > 0) line["held_back"] = entry.held_back;
  // Invalid UTF-8 from a caller (a worker id, a peer name) is replaced rather than thrown.
  const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  std::lock_guard lock(mutex_);  // a part line is cut back before another line follows it
  const ssize_t written = ::write(fd_, text.data(), text.size());
  if (written == static_cast<ssize_t>(text.size())) return;
  // A short write (a disk that filled mid-line) reports no errno and left a part line, which the next
  // line was glued to, spoiling both (found 2026-12-07): the part is cut off again.
  const int error = written < 0 ? errno : ENOSPC;
  struct stat status {};
  if (written > 0 && ::fstat(fd_, &status) == 0 && S_ISREG(status.st_mode) && status.st_size >= written)
    static_cast<void>(::ftruncate(fd_, status.st_size - written));
  spdlog::error("audit log {}: write failed: {}", path_.string(), std::strerror(error));
  if (on_failure_) on_failure_();
}

}  // namespace endorecon::server
