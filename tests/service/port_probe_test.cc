// server::CheckPortFree: a taken port is told before the server opens its data folder.
#include "server/port_probe.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"

namespace endorecon::server {
namespace {

TEST(PortProbeTest, ATakenPortIsToldAndAFreeOneIsNot) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  socklen_t length = sizeof(address);
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length), 0);
  const std::string listen = "127.0.0.1:" + std::to_string(ntohs(address.sin_port));
  const std::string message = testing::ErrorFrom([&] { CheckPortFree(listen); }, ErrorCode::kUnavailable);
  EXPECT_NE(message.find("cannot listen on " + listen + ": the port is taken"), std::string::npos) << message;
  ::close(fd);
  EXPECT_NO_THROW(CheckPortFree(listen));
  EXPECT_NO_THROW(CheckPortFree("127.0.0.1:0"));
  EXPECT_NO_THROW(CheckPortFree("unix:/tmp/endorecon.sock"));
  EXPECT_NO_THROW(CheckPortFree("no-such-host.invalid:50051")) << "left to gRPC";
}

}  // namespace
}  // namespace endorecon::server
