// gRPC's own log lines (its C core's gpr_log: a failed TLS handshake, a refused connection) into the
// process's log (spdlog), repeats of a line paced (once per 30 s, with their count), and each failed
// TLS handshake counted. The server's and the worker's: the worker's stderr took two bare lines a
// second while its --ca did not verify the server (found 2026-12-07). A handshake fails before any call, so
// nothing else saw it: a worker presenting a certificate of another CA retried every second for hours,
// writing a bare line to stderr each time, while endorecon_calls_refused_total stayed 0 and no alert fired
// (found 2026-12-07).
#pragma once

#include <functional>
#include <string>

namespace endorecon {

// Installs the route for the process (gRPC's log is process-wide); `handshake_failed` is called for
// each failed TLS handshake while the route lives (the lines still go to the log after), and
// `handshake_hint` follows a handshake's line (what it means on this side). GRPC_VERBOSITY still
// picks which lines gRPC writes (ERROR by default).
class GrpcLogRoute {
 public:
  GrpcLogRoute(std::string handshake_hint, std::function<void()> handshake_failed);
  ~GrpcLogRoute();
  GrpcLogRoute(const GrpcLogRoute&) = delete;
  GrpcLogRoute& operator=(const GrpcLogRoute&) = delete;

  // Logs the counts of repeats held back whose 30 s are over with no repeat since to carry them
  // ("grpc: LINE (N more like it in the last 30 s)"): call it now and then (the server's maintenance
  // thread, each second).
  void FlushHeldBack() const;
};

}  // namespace endorecon
