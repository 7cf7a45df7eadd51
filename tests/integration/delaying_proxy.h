// A TCP proxy on loopback that holds each new connection for a while before it reaches the server:
// what a client meets on a far or congested link, where the TLS and HTTP/2 handshakes take a second.
#pragma once

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace endorecon::testing {

class DelayingProxy {
 public:
  // Listens on a free 127.0.0.1 port; each connection reaches 127.0.0.1:`upstream_port` after `delay`.
  DelayingProxy(int upstream_port, std::chrono::milliseconds delay);
  ~DelayingProxy();
  DelayingProxy(const DelayingProxy&) = delete;
  DelayingProxy& operator=(const DelayingProxy&) = delete;

  int port() const { return port_; }

 private:
  void Accept();
  void Relay(int client) const;

  int upstream_port_;
  std::chrono::milliseconds delay_;
  int listener_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread acceptor_;
  std::vector<std::thread> relays_;  // touched by the acceptor only, joined after it
};

}  // namespace endorecon::testing
