#include "common/secret_file.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "common/transport_security.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {
namespace fs = std::filesystem;

TEST(SecretFileTest, RefusesFilesOthersMayAccessAndAcceptsGroupRead) {
  testing::TempDir dir("secret");
  const auto key = dir / "server.key";
  testing::WriteBytes(key, "-----BEGIN PRIVATE KEY-----\n");
  fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(ReadSecretFile(key, "--tls-key"), "-----BEGIN PRIVATE KEY-----\n");
  fs::permissions(key, fs::perms::others_read, fs::perm_options::add);
  try {
    ReadSecretFile(key, "--tls-key");
    ADD_FAILURE() << "a world-readable key was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    const std::string message = e.what();
    EXPECT_NE(message.find("--tls-key"), std::string::npos) << message;
    EXPECT_NE(message.find("0644"), std::string::npos) << message;
    EXPECT_NE(message.find("chmod 600 "), std::string::npos) << message;
  }
  EXPECT_NE(
      testing::ErrorFrom([&] { ReadSecretFile(dir / "missing.key", "--tls-key"); }, ErrorCode::kNotFound)
          .find("missing.key: no such file"),
      std::string::npos);
}

// A file that is there but cannot be reached (a folder this user may not enter; root enters every
// folder, so a symbolic link loop stands in) is not "no such file" (found 2026-12-07).
TEST(SecretFileTest, AFileThatCannotBeReachedSaysWhy) {
  testing::TempDir dir("secret");
  fs::create_symlink(dir / "b", dir / "a");
  fs::create_symlink(dir / "a", dir / "b");
  const std::string message =
      testing::ErrorFrom([&] { ReadSecretFile(dir / "a", "--token-file"); }, ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("--token-file " + (dir / "a").string() + ": cannot be read: Too many levels of"),
            std::string::npos)
      << message;
}

// A token with a trailing newline in $ENDORECON_TOKEN, or a BOM or control byte in its file, aborted the
// CLI and the worker in gRPC's header check (found 2026-12-05): trimmed, or refused naming the byte.
TEST(SecretFileTest, ATokenIsOneWordOfPrintableAscii) {
  EXPECT_EQ(CleanToken("endorecon.abc.def\n", "$ENDORECON_TOKEN"), "endorecon.abc.def");
  EXPECT_EQ(CleanToken("\xEF\xBB\xBF"
                       "endorecon.abc.def\r\n",
                       "$ENDORECON_TOKEN"),
            "endorecon.abc.def");
  EXPECT_EQ(CleanToken(" endorecon.abc.def\t", "$ENDORECON_TOKEN"), "endorecon.abc.def");
  const std::string message = testing::ErrorFrom(
      [] {
        CleanToken(std::string("endorecon.a\x01"
                               "c.def"),
                   "$ENDORECON_TOKEN");
      },
      ErrorCode::kUnauthenticated);
  EXPECT_NE(message.find("$ENDORECON_TOKEN: the token holds byte 0x01 at position 12"), std::string::npos)
      << message;
  EXPECT_THROW(CleanToken("endorecon.\xC3\xA9.def", "--token-file t"), Error);
  EXPECT_THROW(CleanToken("  ", "--token-file t"), Error);
}

TEST(SecretFileTest, TokenFilesHoldOneWord) {
  testing::TempDir dir("secret");
  const auto token = dir / "token";
  testing::WriteBytes(token, "  endorecon.abc.def\n");
  fs::permissions(token, fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(ReadTokenFile(token, "--token-file"), "endorecon.abc.def");
  testing::WriteBytes(token, "two words\n");
  EXPECT_THROW(ReadTokenFile(token, "--token-file"), Error);
  testing::WriteBytes(token, "\n");
  EXPECT_THROW(ReadTokenFile(token, "--token-file"), Error);
  // An empty file is there but of no use: a bad argument, not a missing file (it said NOT_FOUND).
  testing::WriteBytes(token, "");
  try {
    ReadTokenFile(token, "--token-file");
    ADD_FAILURE() << "an empty token file was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    EXPECT_NE(std::string(e.what()).find("the file is empty"), std::string::npos) << e.what();
  }
}

TEST(SecretFileTest, ChannelsAndPortsRefuseHalfAConfiguration) {
  EXPECT_THROW(OpenChannel("127.0.0.1:1", {"", "cert.pem", "", ""}), Error);
  EXPECT_THROW(OpenChannel("127.0.0.1:1", {"", "cert.pem", "key.pem", ""}), Error);
  EXPECT_THROW(ServerCredentials({"", "", "ca.pem"}), Error);
  EXPECT_THROW(ServerCredentials({"cert.pem", "", ""}), Error);
}

// What repeats a user's words (CLI11's "arguments were not expected") withholds a token's secret.
TEST(SecretFileTest, MessagesWithholdATokensSecret) {
  EXPECT_EQ(WithoutTokens("not expected: endorecon.069a98af32362ec1.d840c55a0123456789abcdef808880 --token"),
            "not expected: endorecon.069a98af32362ec1.\u2026 --token");
  EXPECT_EQ(WithoutTokens("endorecon.1.2 and endorecon-server"), "endorecon.1.2 and endorecon-server");
}

// A token goes in plaintext only to this machine: the CLI and the worker sent it to any address
// without --ca, where anyone on the path reads it (found 2026-12-06).
TEST(SecretFileTest, ATokenTravelsInPlaintextOnlyOnLoopback) {
  const std::string token = "endorecon.0123456789abcdef.0123456789abcdef0123456789abcdef";
  for (const char* address : {"192.0.2.2:50051", "pacs-gw.hospital:50051", "[2001:db8::1]:50051",
                              "127.evil.example:50051", "localhost.evil.example:50051"}) {
    const std::string refusal = testing::ErrorFrom([&] { OpenChannel(address, {"", "", "", token, ""}); });
    EXPECT_NE(refusal.find("a token is sent only over TLS beyond this machine: give --ca"), std::string::npos)
        << address << ": " << refusal;
  }
  for (const char* address :
       {"127.0.0.1:50051", "127.1.2.3:50051", "localhost:50051", "[::1]:50051", "unix:/run/endorecon.sock"}) {
    EXPECT_NE(OpenChannel(address, {"", "", "", token, ""}), nullptr) << address;
  }
  EXPECT_NE(OpenChannel("192.0.2.2:50051", {}), nullptr) << "no token: nothing to keep";
}

}  // namespace
}  // namespace endorecon
