// What the CLI and the worker add to gRPC's words when a TLS connection fails: which side's setting
// to look at.
#include <gtest/gtest.h>

#include <string>

#include "common/transport_security.h"

namespace endorecon {
namespace {

TEST(TlsFailureHintTest, EachFailureSaysWhichSettingToLookAt) {
  ChannelSecurity security;
  security.ca_file = "ca.crt";
  EXPECT_NE(TlsFailureHint("Handshake failed: CERTIFICATE_VERIFY_FAILED", security)
                .find("does not verify against --ca ca.crt"),
            std::string::npos);
  EXPECT_NE(TlsFailureHint("SSL routines:ssl3_get_record:wrong version number", security)
                .find("does not answer in TLS"),
            std::string::npos);
  // The certificate verified, for other names (no hint until 2026-12-07).
  EXPECT_NE(TlsFailureHint("ipv4:127.0.0.2:50051: Peer name 127.0.0.2 is not in peer certificate", security)
                .find("does not name the address dialled"),
            std::string::npos);
  EXPECT_EQ(TlsFailureHint("Connection refused", security), "");
  EXPECT_EQ(TlsFailureHint("Peer name x is not in peer certificate", ChannelSecurity{}), "")
      << "no TLS asked";
}

}  // namespace
}  // namespace endorecon
