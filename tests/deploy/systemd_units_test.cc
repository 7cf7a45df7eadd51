// The systemd units pass `systemd-analyze verify` (with the built binaries in place of
// /usr/local/bin), and every flag they give a binary is one it accepts.
#include <gtest/gtest.h>

#include "tests/deploy/deploy_files.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

TEST(SystemdUnitsTest, UnitsVerifyAndUseExistingFlags) {
  if (!fs::exists("/usr/bin/systemd-analyze")) GTEST_SKIP() << "systemd-analyze is not installed here";
  TempDir dir("units");
  // A template unit verifies as one of its instances.
  const std::vector<std::pair<std::string, std::string>> units{
      {"endorecon-server.service", "endorecon-server.service"},
      {"endorecon-worker@.service", "endorecon-worker@cpu.service"}};
  for (const auto& unit : units) {
    // Not a structured binding: clang 14 (the sanitizer builds) cannot capture one in a lambda.
    const std::string& source = unit.first;
    const std::string& instance = unit.second;
    std::string text = ReadBytes(SourcePath("deploy/systemd/" + source));
    for (const std::string binary : {"endorecon-server", "endorecon-worker"}) {
      for (auto at = text.find("/usr/local/bin/" + binary); at != std::string::npos;
           at = text.find("/usr/local/bin/" + binary, at)) {
        text.replace(at, 15 + binary.size(), BinaryNamed(binary));
      }
    }
    WriteBytes(dir / instance, text);
    const auto verify = Capture("cd '" + dir.path().string() + "' && systemd-analyze verify './" + instance +
                                "' 2>&1; echo rc=$?");
    EXPECT_EQ(verify, "rc=0\n") << instance;

    const auto flags_of = [&](const std::string& binary, const std::string& subcommand) {
      const auto accepted = AcceptedFlags(BinaryNamed(binary), subcommand);
      const std::regex used("--[a-z][a-z0-9-]*");
      const auto exec = text.substr(text.find("ExecStart="));
      for (auto it = std::sregex_iterator(exec.begin(), exec.end(), used); it != std::sregex_iterator(); ++it)
        EXPECT_TRUE(accepted.count(it->str())) << instance << ": " << binary << " has no " << it->str();
    };
    if (source == "endorecon-server.service") flags_of("endorecon-server", "");
    if (source == "endorecon-worker@.service") flags_of("endorecon-worker", "serve");
  }
}

}  // namespace
}  // namespace endorecon::testing
