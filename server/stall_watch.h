// Ends the server streams whose peer stops reading or sending. A blocking Write of a server stream
// returns only once the peer's flow-control window takes the message, a blocking Read once the
// peer sends; a client or worker that stops (a hung process, a dead NAT mapping that still
// acknowledges) would hold the handler's thread, its buffered chunk and, for an upload, its upload
// slot for as long as the connection lives. Every such Write and every Read of an upload's chunks
// goes through a StallWatch: one that has not returned within the limit cancels its call, the
// Write or Read then returns false and the handler ends, freeing the thread. What a stream holds meanwhile is
// bounded by one message (a 4 MiB chunk) plus gRPC's flow-control window.
#pragma once

#include <grpcpp/server_context.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace endorecon::server {

class StallWatch {
 public:
  explicit StallWatch(std::chrono::milliseconds limit);
  ~StallWatch();
  StallWatch(const StallWatch&) = delete;
  StallWatch& operator=(const StallWatch&) = delete;

  // Runs `operation` (a stream's Write or Read), cancelling `context` if it has not returned within
  // the limit; returns what `operation` returned.
  bool Guard(grpc::ServerContext* context, const std::function<bool()>& operation);

  // Streams cancelled so far for a stalled peer.
  std::uint64_t cancelled() const;

 private:
  void Loop();

  using Clock = std::chrono::steady_clock;
  struct Armed {
    grpc::ServerContext* context;
    Clock::time_point deadline;
  };
  const std::chrono::milliseconds limit_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::uint64_t, Armed> armed_;
  std::uint64_t next_ = 0, cancelled_ = 0;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace endorecon::server
