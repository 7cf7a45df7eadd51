#include "worker/runtime/progress_line.h"

#include <spdlog/sinks/sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <utility>

namespace endorecon::worker {
namespace {

std::mutex progress_mutex;
bool line_open = false;
// Into a pipe or a file, a line rewritten with "\r" is one line of every update (a log of a long run
// held thousands); there the progress is a line of its own at most every kPipedInterval.
constexpr std::chrono::seconds kPipedInterval{10};
std::chrono::steady_clock::time_point piped_at;
bool piped_once = false;

// A logger's sink that ends the progress line before the message it passes on.
class EndsProgressSink final : public spdlog::sinks::sink {
 public:
  explicit EndsProgressSink(spdlog::sink_ptr inner) : inner_(std::move(inner)) {}
  void log(const spdlog::details::log_msg& message) override {
    EndProgress();
    inner_->log(message);
  }
  void flush() override { inner_->flush(); }
  void set_pattern(const std::string& pattern) override { inner_->set_pattern(pattern); }
  void set_formatter(std::unique_ptr<spdlog::formatter> formatter) override {
    inner_->set_formatter(std::move(formatter));
  }

 private:
  spdlog::sink_ptr inner_;
};

}  // namespace

void ShowProgress(const std::string& text) {
  const std::lock_guard lock(progress_mutex);
  static const bool terminal = isatty(STDERR_FILENO) != 0;
  if (!terminal) {
    const auto now = std::chrono::steady_clock::now();
    if (piped_once && now - piped_at < kPipedInterval) return;
    piped_once = true;
    piped_at = now;
    std::fprintf(stderr, "%s\n", text.c_str());
    std::fflush(stderr);
    return;
  }
  std::fprintf(stderr, "\r%s", text.c_str());
  std::fflush(stderr);
  line_open = true;
}

void EndProgress() {
  const std::lock_guard lock(progress_mutex);
  if (!line_open) return;
  std::fputc('\n', stderr);
  std::fflush(stderr);
  line_open = false;
}

void EndProgressBeforeEachLog() {
  for (spdlog::sink_ptr& sink : spdlog::default_logger()->sinks()) {
    sink = std::make_shared<EndsProgressSink>(sink);
  }
}

}  // namespace endorecon::worker
