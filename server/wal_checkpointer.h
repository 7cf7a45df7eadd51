// Checkpoints a SQLite database in WAL mode on a thread of its own. SQLite's automatic checkpoint
// runs inside the COMMIT that takes the log past 1,000 pages: that commit copies the log into the
// database file and fsyncs it too, 4-6 times a plain commit on an idle disk (bench/service_load's
// slowest commits were these), and a group commit makes every writer of its batch wait for it.
// Here the writer's commits only append to the log; a hook on the writer connection wakes this
// thread once the log holds `pages`, and it runs a PASSIVE checkpoint on its own connection, beside
// the writers (never blocking them). Durability is unchanged: a commit is on disk when its log
// frames are (synchronous=FULL), checkpointed or not. Destroy it before closing the writer.
#pragma once

#include <sqlite3.h>

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <thread>

namespace endorecon::server {

class WalCheckpointer {
 public:
  // Takes over `writer`'s checkpoints (its automatic ones are off from here on). Throws
  // Error(kUnavailable) naming `store` when the database cannot be opened.
  WalCheckpointer(const std::filesystem::path& db_file, sqlite3* writer, const char* store, int pages = 1000);
  ~WalCheckpointer();
  WalCheckpointer(const WalCheckpointer&) = delete;
  WalCheckpointer& operator=(const WalCheckpointer&) = delete;

  // Checkpoints run so far, failed ones included (a failure is logged as a warning).
  std::uint64_t checkpoints();

 private:
  static int OnCommit(void* self, sqlite3* db, const char* name, int log_pages);
  void Loop();

  sqlite3* writer_;
  const char* store_;
  int pages_;
  sqlite3* db_ = nullptr;  // the checkpointer's own connection
  std::mutex mutex_;
  std::condition_variable wake_;
  bool due_ = false;
  bool stop_ = false;
  std::uint64_t checkpoints_ = 0;
  std::thread thread_;
};

}  // namespace endorecon::server
