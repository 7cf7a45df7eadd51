#include "tests/integration/delaying_proxy.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <stdexcept>

namespace endorecon::testing {
namespace {

sockaddr_in Loopback(int port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return address;
}

// Copies what `from` has to `to`; false when `from` closed or either failed.
bool Pump(int from, int to) {
  char buffer[16384];
  const ssize_t got = read(from, buffer, sizeof(buffer));
  if (got <= 0) return false;
  for (ssize_t sent = 0; sent < got;) {
    const ssize_t n = write(to, buffer + sent, static_cast<std::size_t>(got - sent));
    if (n <= 0) return false;
    sent += n;
  }
  return true;
}

}  // namespace

DelayingProxy::DelayingProxy(int upstream_port, std::chrono::milliseconds delay)
    : upstream_port_(upstream_port), delay_(delay) {
  listener_ = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address = Loopback(0);
  socklen_t length = sizeof(address);
  if (listener_ < 0 || bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
      listen(listener_, 16) != 0 ||
      getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length) != 0)
    throw std::runtime_error("DelayingProxy: cannot listen on 127.0.0.1");
  port_ = ntohs(address.sin_port);
  acceptor_ = std::thread([this] { Accept(); });
}

DelayingProxy::~DelayingProxy() {
  stop_ = true;
  acceptor_.join();
  for (auto& relay : relays_) relay.join();
  close(listener_);
}

void DelayingProxy::Accept() {
  while (!stop_) {
    pollfd ready{listener_, POLLIN, 0};
    if (poll(&ready, 1, 100) <= 0) continue;
    const int client = accept(listener_, nullptr, nullptr);
    if (client >= 0) relays_.emplace_back([this, client] { Relay(client); });
  }
}

void DelayingProxy::Relay(int client) const {
  // The client's first bytes (its HTTP/2 preface, or its TLS hello) wait in the socket meanwhile.
  for (auto waited = std::chrono::milliseconds(0); waited < delay_ && !stop_;
       waited += std::chrono::milliseconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const int server = socket(AF_INET, SOCK_STREAM, 0);
  const sockaddr_in address = Loopback(upstream_port_);
  if (server >= 0 && connect(server, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0) {
    pollfd ends[2] = {{client, POLLIN, 0}, {server, POLLIN, 0}};
    while (!stop_) {
      if (poll(ends, 2, 100) <= 0) continue;
      if ((ends[0].revents & (POLLIN | POLLHUP | POLLERR)) && !Pump(client, server)) break;
      if ((ends[1].revents & (POLLIN | POLLHUP | POLLERR)) && !Pump(server, client)) break;
    }
  }
  if (server >= 0) close(server);
  close(client);
}

}  // namespace endorecon::testing
