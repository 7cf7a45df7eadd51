#include "server/health_port.h"

#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/server_builder.h>

#include "common/error.h"

namespace endorecon::server {

HealthPort::HealthPort(const std::string& address) {
  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(address, grpc::InsecureServerCredentials(), &port_);
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);  // as the main port (main.cc)
  // gRPC 1.51 builds no server without a synchronous method or a frequently polled queue; the
  // default health service needs neither, so this queue only satisfies the builder and is drained.
  queue_ = builder.AddCompletionQueue(true);
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) Fail(ErrorCode::kUnavailable, "cannot listen on --health-listen " + address);
  drain_ = std::thread([this] {
    void* tag = nullptr;
    bool ok = false;
    while (queue_->Next(&tag, &ok)) {
    }
  });
}

HealthPort::~HealthPort() {
  server_->Shutdown(std::chrono::system_clock::now());
  queue_->Shutdown();
  drain_.join();
}

void HealthPort::SetServing(bool serving) { server_->GetHealthCheckService()->SetServingStatus(serving); }

}  // namespace endorecon::server
