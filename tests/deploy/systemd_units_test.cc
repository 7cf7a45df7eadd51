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

// The worker unit's command line as systemd runs it for an instance (its specifiers replaced, $$ a
// dollar for the shell, continuation lines joined), with `echo` for the worker: each instance gets
// its own metrics port, and METRICS_PORT set with `systemctl edit` wins.
std::string WorkerCommandLine(const std::string& instance, const std::string& environment) {
  std::string exec = ReadBytes(SourcePath("deploy/systemd/endorecon-worker@.service"));
  exec = exec.substr(exec.find("ExecStart=") + 10);
  std::string line;
  for (std::size_t i = 0; i < exec.size() && exec[i] != '\n'; ++i) {
    if (exec[i] == '\\' && i + 1 < exec.size() && exec[i + 1] == '\n') {
      ++i;
      continue;
    }
    line += exec[i];
  }
  const std::vector<std::pair<std::string, std::string>> specifiers{
      {"%i", instance},
      {"%d", "/run/credentials/x"},
      {"%H", "node7"},
      {"$$", "$"},
      {"/usr/local/bin/endorecon-worker", "echo"}};
  for (const auto& [from, to] : specifiers) {
    for (auto at = line.find(from); at != std::string::npos; at = line.find(from, at + to.size()))
      line.replace(at, from.size(), to);
  }
  return Capture("ENDORECON_SERVER=head:50051 CACHE_DIRECTORY=/var/cache/w " + environment + " " + line);
}

TEST(SystemdUnitsTest, EachWorkerInstanceServesMetricsOnItsOwnPort) {
  EXPECT_NE(WorkerCommandLine("cpu", "").find("--devices cpu "), std::string::npos);
  EXPECT_NE(WorkerCommandLine("cpu", "").find("--metrics-port 9465 "), std::string::npos);
  EXPECT_NE(WorkerCommandLine("0", "").find("--metrics-port 9465 "), std::string::npos);
  const std::string second = WorkerCommandLine("1", "");
  EXPECT_NE(second.find("--metrics-port 9466 --work-dir /var/cache/w --id node7-1"), std::string::npos)
      << second;
  EXPECT_NE(second.find("--server head:50051 --devices 1 "), std::string::npos) << second;
  EXPECT_NE(WorkerCommandLine("1", "METRICS_PORT=9500").find("--metrics-port 9500 "), std::string::npos);
}

}  // namespace
}  // namespace endorecon::testing
