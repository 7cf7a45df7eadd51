#include "common/grpc_log.h"

#include <grpc/support/log.h>
#include <spdlog/spdlog.h>

#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/warning_pacer.h"

namespace endorecon {
namespace {

struct Route {
  std::mutex mutex;
  std::function<void()> handshake_failed;
  std::string handshake_hint;
  // By the line's source and text: its pacer, and the line and level to say a held count with.
  struct Paced {
    WarningPacer pacer;
    std::string line;
    spdlog::level::level_enum level = spdlog::level::err;
  };
  std::map<std::string, Paced> pacers;
};

spdlog::level::level_enum LevelOf(gpr_log_severity severity) {
  return severity == GPR_LOG_SEVERITY_ERROR  ? spdlog::level::err
         : severity == GPR_LOG_SEVERITY_INFO ? spdlog::level::info
                                             : spdlog::level::debug;
}

std::string HeldText(int held) {
  return held > 0 ? " (" + std::to_string(held) + " more like it in the last 30 s)" : "";
}

Route& TheRoute() {
  static Route route;
  return route;
}

void Log(gpr_log_func_args* args) {
  auto& route = TheRoute();
  const std::string_view message = args->message ? args->message : "";
  const bool handshake = message.find("Handshake failed") != std::string_view::npos;
  std::function<void()> count;
  std::string hint;
  int held = 0;
  bool due = false;
  {
    std::lock_guard lock(route.mutex);
    if (handshake) {
      count = route.handshake_failed;
      hint = route.handshake_hint;
    }
    // Paced by where it comes from and what it says: a client retrying every second makes the same
    // line each time, and a plaintext client's failure is not lumped with a rogue certificate's. The
    // messages are gRPC's own few; should they vary without end, the count restarts.
    if (route.pacers.size() > 256) route.pacers.clear();
    auto& paced = route.pacers[std::string(args->file ? args->file : "") + ":" + std::to_string(args->line) +
                               ":" + std::string(message.substr(0, 160))];
    due = paced.pacer.Due(held);
    paced.line = std::string(message) + (hint.empty() ? "" : " (" + hint + ")");
    paced.level = LevelOf(args->severity);
  }
  if (count) count();
  if (!due) return;
  spdlog::log(LevelOf(args->severity), "grpc: {}{}{}", message, hint.empty() ? "" : " (" + hint + ")",
              HeldText(held));
}

}  // namespace

GrpcLogRoute::GrpcLogRoute(std::string handshake_hint, std::function<void()> handshake_failed) {
  {
    std::lock_guard lock(TheRoute().mutex);
    TheRoute().handshake_failed = std::move(handshake_failed);
    TheRoute().handshake_hint = std::move(handshake_hint);
  }
  gpr_set_log_function(Log);
}

void GrpcLogRoute::FlushHeldBack() const {
  std::vector<std::pair<spdlog::level::level_enum, std::string>> lines;
  {
    std::lock_guard lock(TheRoute().mutex);
    for (auto& [key, paced] : TheRoute().pacers) {
      int held = 0;
      if (paced.pacer.Overdue(held)) lines.emplace_back(paced.level, paced.line + HeldText(held - 1));  // the line is one
    }
  }
  for (const auto& [level, line] : lines) spdlog::log(level, "grpc: {}", line);
}

GrpcLogRoute::~GrpcLogRoute() {
  std::lock_guard lock(TheRoute().mutex);
  TheRoute().handshake_failed = nullptr;
  TheRoute().handshake_hint.clear();
}

}  // namespace endorecon
