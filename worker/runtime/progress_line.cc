#include "worker/runtime/progress_line.h"

#include <spdlog/sinks/sink.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <mutex>
#include <utility>

namespace endorecon::worker {
namespace {

std::mutex progress_mutex;
bool line_open = false;

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
