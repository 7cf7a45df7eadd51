#include "common/file_download.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "common/error.h"
#include "common/grpc_status.h"
#include "common/safe_path.h"
#include "common/sha256.h"

namespace endorecon {
namespace fs = std::filesystem;
namespace {

fs::path PartPath(const fs::path& target) { return fs::path(target.string() + ".part"); }

// One file being received: appends to its .part, then verifies and renames.
class PartialFile {
 public:
  PartialFile(const fs::path& dir, const v1::FileEntry& entry, std::int64_t offset) : entry_(entry) {
    CheckRelativePath(entry.path());
    target_ = dir / entry.path();
    std::error_code error;
    fs::create_directories(target_.parent_path(), error);
    // A path under another file's name (a/b after a file a) cannot be made
    // (tests/fuzz/download_stream_fuzz.cc).
    if (error) {
      FailInvalid("download of '" + entry.path() + "': cannot make its folder " +
                  target_.parent_path().string() + ": " + error.message());
    }
    const auto part = PartPath(target_);
    const std::int64_t have = fs::exists(part) ? static_cast<std::int64_t>(fs::file_size(part)) : 0;
    if (offset > have) FailInvalid("download of '" + entry.path() + "' starts past its partial file");
    if (fs::exists(part)) fs::resize_file(part, static_cast<std::uintmax_t>(offset));
    out_.open(part, std::ios::binary | std::ios::app);
    if (!out_) Fail(ErrorCode::kInternal, "cannot write " + part.string());
    written_ = offset;
  }

  void Append(std::int64_t offset, const std::string& data) {
    if (offset != written_) {
      FailInvalid("chunk of '" + entry_.path() + "' at offset " + std::to_string(offset) + ", expected " +
                  std::to_string(written_));
    }
    errno = 0;
    out_.write(data.data(), static_cast<std::streamsize>(data.size()));
    if (!out_) WriteFailed(errno);
    written_ += static_cast<std::int64_t>(data.size());
  }

  bool Done() const { return written_ >= entry_.size(); }

  void Finish() {
    errno = 0;
    out_.close();
    if (!out_) WriteFailed(errno);
    const auto part = PartPath(target_);
    const auto digest = Sha256File(part);
    if (digest != entry_.sha256()) {
      fs::remove(part);
      Fail(ErrorCode::kDataLoss, "'" + entry_.path() + "' arrived with sha256 " + digest + ", expected " +
                                     entry_.sha256() + "; removed, download it again");
    }
    fs::rename(part, target_);
  }

 private:
  // A write the disk refused says so, with the system's words (a full disk is RESOURCE_EXHAUSTED and
  // reads "No space left on device", which the job runner takes for its scratch folder's fault).
  // Unchecked, the short file failed its digest and was reported as data lost in transit. Any other
  // local failure is INTERNAL, not UNAVAILABLE: it is no server's, and a call retried while the server
  // is unavailable would retry it for ever (the CLI said "server unavailable" for a file too large).
  [[noreturn]] void WriteFailed(int error) const {
    const bool full = error == ENOSPC || error == EDQUOT;
    Fail(full ? ErrorCode::kResourceExhausted : ErrorCode::kInternal,
         "cannot write " + PartPath(target_).string() + ": " +
             (error != 0 ? std::strerror(error) : "the write failed") + "; what arrived so far is kept");
  }

  v1::FileEntry entry_;
  fs::path target_;
  std::ofstream out_;
  std::int64_t written_ = 0;
};

}  // namespace

std::vector<v1::FileRange> PendingDownloads(const fs::path& dir, const v1::Manifest& manifest) {
  std::vector<v1::FileRange> pending;
  for (const auto& entry : manifest.files()) {
    CheckRelativePath(entry.path());
    const auto target = dir / entry.path();
    if (fs::is_regular_file(target) && static_cast<std::int64_t>(fs::file_size(target)) == entry.size() &&
        Sha256File(target) == entry.sha256()) {
      continue;
    }
    const auto part = PartPath(target);
    std::int64_t offset = fs::is_regular_file(part) ? static_cast<std::int64_t>(fs::file_size(part)) : 0;
    if (offset > entry.size()) offset = 0;
    v1::FileRange range;
    range.set_path(entry.path());
    range.set_sha256(entry.sha256());
    range.set_offset(offset);
    pending.push_back(range);
  }
  return pending;
}

std::vector<v1::FileRange> OnePerContent(const std::vector<v1::FileRange>& pending) {
  std::vector<v1::FileRange> unique;
  std::set<std::string> asked;
  for (const auto& range : pending) {
    if (asked.insert(range.sha256()).second) unique.push_back(range);
  }
  return unique;
}

void CopyDuplicates(const fs::path& dir, const std::vector<v1::FileRange>& pending) {
  std::map<std::string, fs::path> received;  // content -> the file of it received
  for (const auto& range : OnePerContent(pending)) received.emplace(range.sha256(), dir / range.path());
  for (const auto& range : pending) {
    const auto target = dir / range.path();
    const auto& source = received.at(range.sha256());
    if (target == source) continue;
    std::error_code error;
    fs::create_directories(target.parent_path(), error);
    if (!error) fs::copy_file(source, target, fs::copy_options::overwrite_existing, error);
    // As a received file's write (WriteFailed): a full disk is RESOURCE_EXHAUSTED, anything else
    // INTERNAL, never UNAVAILABLE, which a download retried while the server is away would retry.
    if (error) {
      const bool full = error.value() == ENOSPC || error.value() == EDQUOT;
      Fail(full ? ErrorCode::kResourceExhausted : ErrorCode::kInternal,
           "cannot write " + target.string() + ": " + error.message());
    }
    fs::remove(PartPath(target), error);
  }
}

std::int64_t ReceiveFiles(grpc::ClientReaderInterface<v1::FileChunk>& reader, const fs::path& dir) {
  std::int64_t received = 0;
  std::optional<PartialFile> current;
  v1::FileChunk chunk;
  while (reader.Read(&chunk)) {
    if (chunk.has_file()) {
      if (current)
        FailInvalid("a new file began before '" + chunk.file().path() + "'s predecessor was complete");
      current.emplace(dir, chunk.file(), chunk.offset());
    }
    if (!current) FailInvalid("a chunk arrived before its file's header");
    current->Append(chunk.offset(), chunk.data());
    received += static_cast<std::int64_t>(chunk.data().size());
    if (current->Done()) {
      current->Finish();
      current.reset();
    }
  }
  ThrowIfFailed(reader.Finish(), "download");
  if (current) Fail(ErrorCode::kUnavailable, "the download stream ended inside a file; run again to resume");
  return received;
}

void SyncFolder(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0 || ::syncfs(fd) != 0) {
    const int error = errno;
    if (fd >= 0) ::close(fd);
    Fail(ErrorCode::kInternal, "cannot write " + dir.string() + " to its disk: " + std::strerror(error));
  }
  ::close(fd);
}

}  // namespace endorecon
