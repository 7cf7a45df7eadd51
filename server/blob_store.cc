#include "server/blob_store.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "common/error.h"
#include "common/sha256.h"
#include "server/access_failure.h"

namespace endorecon::server {
namespace fs = std::filesystem;
namespace {

// Write-behind: once this many bytes of a blob are written, the writer asks the kernel to start
// writing them out (sync_file_range, SYNC_FILE_RANGE_WRITE: starts the writeback, does not wait).
// Without it an upload's bytes stay dirty in the page cache until its fdatasync at the end; 100
// uploads ending together then flush 1 GiB in one burst, and the job store's commit, which fsyncs
// the same disk, waited behind it for 100-250 ms (bench/service_load, docs/benchmarks.md). With it
// the bytes reach the disk while they arrive, and the final fdatasync has little left to do.
constexpr std::int64_t kWriteBehindBytes = 4 << 20;

// A full disk (ENOSPC, EDQUOT) is a limit that lifts once space is freed: RESOURCE_EXHAUSTED, so the
// uploader keeps its committed bytes and retries later; other failures are UNAVAILABLE.
[[noreturn]] void FailErrno(const std::string& what, const fs::path& path, int error = errno) {
  const std::string message = what + " " + path.string() + ": " + std::strerror(error);
  if (error == ENOSPC || error == EDQUOT) {
    Fail(ErrorCode::kResourceExhausted,
         message + " (the server's data disk is full; committed bytes are kept)");
  }
  Fail(ErrorCode::kUnavailable, message);
}

void FsyncDirectory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) FailErrno("cannot open directory", dir);
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    errno = error;
    FailErrno("cannot sync directory", dir);
  }
  ::close(fd);
}

// A folder of the store this user cannot list, read or write: a restore chowned without -R. Every
// job then failed as if its files were gone ("no blob ...: set aside as damaged?"), for good (found
// 2026-12-07); refused at start instead.
void RequireUsable(const fs::path& dir) {
  if (::access(dir.c_str(), R_OK | W_OK | X_OK) != 0)
    FailAccess(dir.string() + ": this user cannot use it", errno);
}

}  // namespace

BlobStore::BlobStore(fs::path root) : root_(std::move(root)) {
  fs::create_directories(root_ / "blobs");
  fs::create_directories(root_ / "partial");
  // damaged/ is made when a file is first set aside: one another user owns made a damaged file be
  // deleted instead, its evidence lost (found 2026-12-07).
  if (std::error_code error; fs::is_directory(root_ / "damaged", error)) RequireUsable(root_ / "damaged");
  for (const char* folder : {"blobs", "partial"}) {
    RequireUsable(root_ / folder);
    for (const auto& entry : fs::directory_iterator(root_ / folder)) {
      if (entry.is_directory()) RequireUsable(entry.path());
    }
  }
}

bool BlobStore::Has(const std::string& sha256) const {
  return sha256.size() == 64 && fs::is_regular_file(root_ / "blobs" / sha256.substr(0, 2) / sha256);
}

fs::path BlobStore::PathOf(const std::string& sha256) const {
  if (!Has(sha256)) Fail(ErrorCode::kNotFound, "no blob with sha256 " + sha256);
  return root_ / "blobs" / sha256.substr(0, 2) / sha256;
}

std::optional<std::int64_t> BlobStore::SizeOf(const std::string& sha256) const {
  if (sha256.size() != 64) return std::nullopt;
  std::error_code error;
  const fs::path path = root_ / "blobs" / sha256.substr(0, 2) / sha256;
  const auto size = fs::file_size(path, error);
  if (error == std::errc::permission_denied) FailAccess(path.string() + ": this user cannot read it", EACCES);
  if (error) return std::nullopt;
  return static_cast<std::int64_t>(size);
}

bool BlobStore::PromoteIfFull(const v1::FileEntry& entry, const std::string& owner) {
  if (PartialBytes(entry, owner) != entry.size()) return false;
  const auto writer = TryOpenWriter(entry, std::chrono::milliseconds(0), owner);
  if (!writer || !writer->full()) return false;
  writer->Promote();
  return true;
}

bool BlobStore::AdoptPartial(const std::string& sha256, const std::string& owner) {
  const auto from = PartialName(sha256, ""), to = PartialName(sha256, owner);
  std::lock_guard lock(mutex_);
  std::error_code error;
  if (owner.empty() || writing_.count(from) || writing_.count(to) || !fs::exists(PartialPath(from), error) ||
      fs::exists(PartialPath(to), error))
    return false;
  fs::rename(PartialPath(from), PartialPath(to), error);
  return !error;
}

void BlobStore::Remove(const std::string& sha256) {
  if (!Has(sha256)) return;
  std::error_code error;
  fs::remove(root_ / "blobs" / sha256.substr(0, 2) / sha256, error);
  if (error) Fail(ErrorCode::kUnavailable, "cannot delete blob " + sha256 + ": " + error.message());
}

bool BlobStore::Intact(const std::string& sha256) const {
  if (!Has(sha256)) return false;
  try {
    return Sha256File(PathOf(sha256)) == sha256;
  } catch (const Error&) {
    return false;  // unreadable: damaged as far as anyone reading it can tell
  }
}

fs::path BlobStore::SetAsideDamaged(const std::string& sha256, const std::string& what) {
  const fs::path from = root_ / "blobs" / sha256.substr(0, 2) / sha256;
  const auto seconds =
      std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch());
  const fs::path to = root_ / "damaged" / (sha256 + "." + std::to_string(seconds.count()));
  std::error_code error;
  fs::create_directories(to.parent_path(), error);
  if (!error) fs::rename(from, to, error);
  if (error) {
    fs::remove(from, error);  // out of the store at least: the next upload stores it anew
    spdlog::error(
        "stored file {} ({}) is damaged: its bytes no longer hash to their digest (a disk fault?); "
        "deleted, as it could not be set aside",
        sha256, what);
    return {};
  }
  spdlog::error(
      "stored file {} ({}) is damaged: its bytes no longer hash to their digest (a disk fault?); set "
      "aside as {}; the next upload of the content stores it anew",
      sha256, what, to.string());
  return to;
}

bool BlobStore::WasSetAside(const std::string& sha256) const {
  std::error_code error;
  for (fs::directory_iterator it(root_ / "damaged", error), end; !error && it != end; it.increment(error)) {
    if (it->path().filename().string().rfind(sha256 + ".", 0) == 0) return true;
  }
  return false;
}

std::size_t BlobStore::DamagedCount() const {
  std::error_code error;
  std::size_t count = 0;
  for (fs::directory_iterator it(root_ / "damaged", error), end; !error && it != end; it.increment(error))
    ++count;
  return count;
}

std::vector<BlobStore::StoredFile> BlobStore::Files() const {
  std::vector<StoredFile> files;
  const auto add = [&](const fs::directory_entry& entry, std::string sha256, bool partial,
                       std::string owner) {
    std::error_code error;
    if (!entry.is_regular_file(error)) return;
    const auto bytes = entry.file_size(error);
    const auto written = error ? fs::file_time_type{} : entry.last_write_time(error);
    if (!error) {
      files.push_back({std::move(sha256), entry.path(), partial, std::move(owner),
                       static_cast<std::int64_t>(bytes), written});
    }
  };
  std::error_code error;
  for (const auto& shard : fs::directory_iterator(root_ / "blobs", error)) {
    std::error_code inner;
    for (const auto& entry : fs::directory_iterator(shard.path(), inner))
      add(entry, entry.path().filename().string(), false, "");
  }
  std::lock_guard lock(mutex_);
  for (const auto& entry : fs::directory_iterator(root_ / "partial", error)) {
    std::string name = entry.path().filename().string();
    if (!name.ends_with(".part")) continue;
    name.resize(name.size() - 5);  // "<sha256>" or "<sha256>.<owner>" (PartialName)
    if (name.size() < 64 || (name.size() > 64 && (name.size() == 65 || name[64] != '.'))) continue;
    if (writing_.count(name)) continue;
    add(entry, name.substr(0, 64), true, name.size() > 64 ? name.substr(65) : "");
  }
  return files;
}

void BlobStore::Remove(const StoredFile& file) {
  if (!file.partial) return Remove(file.sha256);
  const auto name = PartialName(file.sha256, file.owner);
  std::lock_guard lock(mutex_);      // held while removing: no writer opens the partial meanwhile
  if (writing_.count(name)) return;  // an upload of it began since it was listed
  std::error_code error;
  fs::remove(PartialPath(name), error);
  if (error) Fail(ErrorCode::kUnavailable, "cannot delete " + file.path.string() + ": " + error.message());
}

std::string BlobStore::PartialName(const std::string& sha256, const std::string& owner) {
  return owner.empty() ? sha256 : sha256 + "." + owner;
}

fs::path BlobStore::PartialPath(const std::string& name) const {
  return root_ / "partial" / (name + ".part");
}

std::int64_t BlobStore::Committed(const v1::FileEntry& entry, const std::string& owner) const {
  return Has(entry.sha256()) ? entry.size() : PartialBytes(entry, owner);
}

std::int64_t BlobStore::PartialBytes(const v1::FileEntry& entry, const std::string& owner) const {
  std::error_code error;
  const auto size = fs::file_size(PartialPath(PartialName(entry.sha256(), owner)), error);
  if (error) return 0;
  return std::min(static_cast<std::int64_t>(size), entry.size());
}

std::unique_ptr<BlobStore::Writer> BlobStore::OpenWriter(const v1::FileEntry& entry,
                                                         const std::string& owner) {
  auto writer = TryOpenWriter(entry, std::chrono::milliseconds(0), owner);
  if (!writer) {
    Fail(ErrorCode::kFailedPrecondition, "'" + entry.path() + "' (sha256 " + entry.sha256() +
                                             ") is being uploaded by another stream right now");
  }
  return writer;
}

std::unique_ptr<BlobStore::Writer> BlobStore::TryOpenWriter(const v1::FileEntry& entry,
                                                            std::chrono::milliseconds wait,
                                                            const std::string& owner) {
  auto name = PartialName(entry.sha256(), owner);
  {
    std::unique_lock lock(mutex_);
    const bool free = released_.wait_for(lock, wait, [&] { return writing_.count(name) == 0; });
    if (!free) return nullptr;
    writing_.insert(name);
  }
  try {
    return std::unique_ptr<Writer>(new Writer(*this, entry, name));
  } catch (...) {
    Release(name);
    throw;
  }
}

void BlobStore::Release(const std::string& name) {
  {
    std::lock_guard lock(mutex_);
    writing_.erase(name);
  }
  released_.notify_all();
}

std::string BlobStore::Put(std::string_view bytes) {
  v1::FileEntry entry;
  entry.set_path("blob");
  entry.set_size(static_cast<std::int64_t>(bytes.size()));
  entry.set_sha256(Sha256Hex(bytes));
  if (Has(entry.sha256())) return entry.sha256();
  auto writer = OpenWriter(entry);
  writer->Append(writer->committed(), bytes.substr(static_cast<std::size_t>(writer->committed())));
  writer->Promote();
  return entry.sha256();
}

BlobStore::Writer::Writer(BlobStore& store, const v1::FileEntry& entry, std::string name)
    : store_(store), entry_(entry), name_(std::move(name)), partial_(store.PartialPath(name_)) {
  fd_ = ::open(partial_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) FailErrno("cannot open", partial_);
  try {  // a constructor that throws runs no destructor: the descriptor is closed here
    const off_t size = ::lseek(fd_, 0, SEEK_END);
    if (size > entry_.size() && ::ftruncate(fd_, 0) != 0) FailErrno("cannot truncate", partial_);
    committed_ = size > entry_.size() ? 0 : static_cast<std::int64_t>(size);
    written_back_ = committed_;
    // The digest covers the whole file, so the bytes committed by earlier streams are read once.
    std::array<char, 1 << 16> buffer{};
    std::int64_t done = 0;
    while (done < committed_) {
      const ssize_t n = ::pread(fd_, buffer.data(), buffer.size(), done);
      if (n <= 0) FailErrno("cannot read", partial_);
      digest_.Update(buffer.data(), static_cast<std::size_t>(n));
      done += n;
    }
    ::lseek(fd_, committed_, SEEK_SET);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

BlobStore::Writer::~Writer() {
  if (fd_ >= 0) {
    ::fdatasync(fd_);
    ::close(fd_);
  }
  // A writer opened while another stream finished the same content (parallel uploads of one clip)
  // made an empty partial file that nothing would use: 8 parallel submits left 27 (found 2026-12-05).
  // One with bytes is kept: another tenant's content, sent again as proof, resumes from it.
  if (committed_ == 0 && store_.Has(entry_.sha256())) {
    std::error_code ignored;
    fs::remove(partial_, ignored);
  }
  store_.Release(name_);
}

void BlobStore::Writer::Append(std::int64_t offset, std::string_view data) {
  if (offset > committed_ || offset < 0) {
    Fail(ErrorCode::kFailedPrecondition, "chunk of '" + entry_.path() + "' starts at offset " +
                                             std::to_string(offset) + " but " + std::to_string(committed_) +
                                             " bytes are committed; continue from there");
  }
  // Bytes sent again (a client resuming from an older answer) are skipped; the digest at the end
  // still vouches for the whole file.
  const auto overlap = static_cast<std::size_t>(std::min<std::int64_t>(committed_ - offset, data.size()));
  data.remove_prefix(overlap);
  if (committed_ + static_cast<std::int64_t>(data.size()) > entry_.size()) {
    FailInvalid("chunk of '" + entry_.path() + "' runs to byte " +
                std::to_string(committed_ + static_cast<std::int64_t>(data.size())) +
                " past its declared size " + std::to_string(entry_.size()));
  }
  std::size_t written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(fd_, data.data() + written, data.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      FailErrno("cannot write", partial_);
    }
    written += static_cast<std::size_t>(n);
  }
  digest_.Update(data);
  committed_ += static_cast<std::int64_t>(data.size());
  if (committed_ - written_back_ >= kWriteBehindBytes) {
    // Only a hint: a kernel or file system that refuses it leaves the work to the fdatasync.
    ::sync_file_range(fd_, written_back_, committed_ - written_back_, SYNC_FILE_RANGE_WRITE);
    written_back_ = committed_;
  }
}

void BlobStore::Writer::Promote() {
  if (!full()) Fail(ErrorCode::kInternal, "promoting an incomplete partial of '" + entry_.path() + "'");
  if (::fdatasync(fd_) != 0) FailErrno("cannot sync", partial_);
  ::close(fd_);
  fd_ = -1;
  const std::string actual = digest_.HexDigest();
  if (actual != entry_.sha256()) {
    fs::remove(partial_);
    Fail(ErrorCode::kDataLoss, "'" + entry_.path() + "' has sha256 " + actual + " but the manifest says " +
                                   entry_.sha256() +
                                   "; its bytes were discarded (did the file change while it was "
                                   "uploaded? upload it again)");
  }
  const fs::path dir = store_.root_ / "blobs" / entry_.sha256().substr(0, 2);
  if (fs::create_directories(dir)) FsyncDirectory(dir.parent_path());  // the new shard's entry too
  fs::rename(partial_, dir / entry_.sha256());
  FsyncDirectory(dir);
}

}  // namespace endorecon::server
