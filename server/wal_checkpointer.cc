#include "server/wal_checkpointer.h"

#include <spdlog/spdlog.h>

#include "server/sqlite_statement.h"

namespace endorecon::server {

WalCheckpointer::WalCheckpointer(const std::filesystem::path& db_file, sqlite3* writer, const char* store,
                                 int pages)
    : writer_(writer), store_(store), pages_(pages), db_(OpenDatabase(db_file, store)) {
  // Replaces the automatic checkpoint, which is itself a WAL hook (sqlite3_wal_autocheckpoint).
  sqlite3_wal_hook(writer_, &WalCheckpointer::OnCommit, this);
  thread_ = std::thread([this] { Loop(); });
}

WalCheckpointer::~WalCheckpointer() {
  sqlite3_wal_hook(writer_, nullptr, nullptr);
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  sqlite3_close(db_);
}

std::uint64_t WalCheckpointer::checkpoints() {
  std::lock_guard lock(mutex_);
  return checkpoints_;
}

int WalCheckpointer::OnCommit(void* self, sqlite3*, const char*, int log_pages) {
  auto* checkpointer = static_cast<WalCheckpointer*>(self);
  if (log_pages >= checkpointer->pages_) {
    {
      std::lock_guard lock(checkpointer->mutex_);
      checkpointer->due_ = true;
    }
    checkpointer->wake_.notify_one();
  }
  return SQLITE_OK;
}

void WalCheckpointer::Loop() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return due_ || stop_; });
    if (stop_) return;
    due_ = false;
    lock.unlock();
    const int rc = sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_PASSIVE, nullptr, nullptr);
    // A failed checkpoint loses nothing (the log still holds every commit); the next commit past
    // the mark asks again.
    if (rc != SQLITE_OK) spdlog::warn("{}: checkpoint failed: {}", store_, sqlite3_errmsg(db_));
    lock.lock();
    ++checkpoints_;
  }
}

}  // namespace endorecon::server
