// A plaintext port that answers grpc.health.v1 only (--health-listen): no API, no data, no tokens,
// for probes that cannot speak TLS (Kubernetes' gRPC probes). Serving while the job store accepts
// writes, as the main port's health service.
#pragma once

#include <grpcpp/server.h>

#include <memory>
#include <string>
#include <thread>

namespace endorecon::server {

class HealthPort {
 public:
  // Listens on `address` ("host:port"; port 0 picks one). Throws Error(kUnavailable) if it cannot.
  explicit HealthPort(const std::string& address);
  ~HealthPort();  // stops listening
  HealthPort(const HealthPort&) = delete;
  HealthPort& operator=(const HealthPort&) = delete;

  void SetServing(bool serving);
  int port() const { return port_; }

 private:
  int port_ = 0;
  std::unique_ptr<grpc::ServerCompletionQueue> queue_;
  std::unique_ptr<grpc::Server> server_;
  std::thread drain_;
};

}  // namespace endorecon::server
