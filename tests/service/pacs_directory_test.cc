// PACS by name: NAME=AET@HOST:PORT flags parsed, bad ones refused with the flag named.
#include "server/pacs_directory.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace endorecon::server {
namespace {

std::string ErrorOf(const std::vector<std::string>& flags) {
  try {
    PacsDirectory directory(flags);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(PacsDirectoryTest, NamesPeersAndRefusesBadFlags) {
  const PacsDirectory directory({"main=PACS1@pacs.hospital:104", "v4=ARCHIVE@[10.0.0.7]:11112"});
  EXPECT_EQ(directory.Find("main").ae_title, "PACS1");
  EXPECT_EQ(directory.Find("main").host, "pacs.hospital");
  EXPECT_EQ(directory.Find("main").port, 104);
  EXPECT_EQ(directory.Find("v4").host, "10.0.0.7");
  EXPECT_EQ(directory.Names(), (std::vector<std::string>{"main", "v4"}));
  try {
    directory.Find("other");
    FAIL() << "an unknown name was found";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("known: main, v4"), std::string::npos) << e.what();
  }
  EXPECT_NE(ErrorOf({"nameonly"}).find("--pacs 'nameonly': expected NAME=AET@HOST:PORT"), std::string::npos);
  EXPECT_NE(ErrorOf({"a=PACS@host:0"}).find("port '0' is not in 1..65535"), std::string::npos);
  EXPECT_NE(ErrorOf({"a=WAY_TOO_LONG_AE_TITLE@host:104"}).find("is not an AE title"), std::string::npos);
  EXPECT_NE(ErrorOf({"a=X@h:1", "a=Y@h:2"}).find("the name 'a' is given twice"), std::string::npos);
  // Taken at start and failing every association "Illegal service parameter" (found 2026-12-07).
  EXPECT_NE(
      ErrorOf({"v6=ARCHIVE@[::1]:11112"}).find("an IPv6 address, which DCMTK's network layer cannot reach"),
      std::string::npos);
  EXPECT_NE(ErrorOf({"a=PACS@host:000000104"}).find("port '000000104' is not in 1..65535"),
            std::string::npos);
}

}  // namespace
}  // namespace endorecon::server
