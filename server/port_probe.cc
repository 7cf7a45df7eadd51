#include "server/port_probe.h"

#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>

#include "common/error.h"

namespace endorecon::server {

void CheckPortFree(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0) return;
  const auto colon = listen.rfind(':');
  if (colon == std::string::npos) return;
  std::string host = listen.substr(0, colon);
  const std::string port = listen.substr(colon + 1);
  if (port.empty() || port == "0") return;
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &found) != 0) return;
  bool taken = false;
  for (const addrinfo* at = found; at != nullptr && !taken; at = at->ai_next) {
    const int fd = ::socket(at->ai_family, at->ai_socktype | SOCK_CLOEXEC, at->ai_protocol);
    if (fd < 0) continue;
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof(on));  // as gRPC: a port in TIME_WAIT is free
    taken = ::bind(fd, at->ai_addr, at->ai_addrlen) != 0 && errno == EADDRINUSE;
    ::close(fd);
  }
  ::freeaddrinfo(found);
  if (taken) {
    Fail(ErrorCode::kUnavailable,
         "cannot listen on " + listen + ": the port is taken (another endorecon-server, or another program)");
  }
}

}  // namespace endorecon::server
