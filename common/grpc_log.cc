#include "common/grpc_log.h"

#include <grpc/support/log.h>
#include <spdlog/spdlog.h>

#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>

#include "common/warning_pacer.h"

namespace endorecon {
namespace {

struct Route {
  std::mutex mutex;
  std::function<void()> handshake_failed;
  std::string handshake_hint;
  std::map<std::string, WarningPacer> pacers;  // by the line's source and severity
};

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
    auto& pacer = route.pacers[std::string(args->file ? args->file : "") + ":" + std::to_string(args->line) +
                               ":" + std::string(message.substr(0, 160))];
    due = pacer.Due(held);
  }
  if (count) count();
  if (!due) return;
  const auto level = args->severity == GPR_LOG_SEVERITY_ERROR  ? spdlog::level::err
                     : args->severity == GPR_LOG_SEVERITY_INFO ? spdlog::level::info
                                                               : spdlog::level::debug;
  spdlog::log(level, "grpc: {}{}{}", message, hint.empty() ? "" : " (" + hint + ")",
              held > 0 ? " (" + std::to_string(held) + " more like it in the last 30 s)" : "");
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

GrpcLogRoute::~GrpcLogRoute() {
  std::lock_guard lock(TheRoute().mutex);
  TheRoute().handshake_failed = nullptr;
  TheRoute().handshake_hint.clear();
}

}  // namespace endorecon
