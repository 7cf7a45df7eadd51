// A local file or folder the user running a command may not use is named, with the reason and the
// user, as input to correct (exit 2): before, the CLI said "filesystem error: status: Permission
// denied [PATH]" with exit 1, and a reconstruction into a folder it could not write loaded the whole
// clip first and failed as "UNAVAILABLE: cannot write run configuration" (found 2026-12-07). Root
// passes every permission check, so the commands run as user nobody.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "tests/integration/service_harness.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::testing {
namespace {
namespace fs = std::filesystem;

constexpr const char* kRunuser = "/usr/sbin/runuser";  // util-linux, in every Debian

CliResult RunAsNobody(const std::vector<std::string>& args) {
  std::vector<std::string> argv{kRunuser, "-u", "nobody", "--"};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunCommand(argv);
}

class LocalPermissionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0 || !fs::exists(kRunuser))
      GTEST_SKIP() << "needs root and runuser, to run the commands as user nobody";
    MakeClip(dir_ / "private");
    fs::permissions(dir_ / "private", fs::perms::owner_all);
    fs::create_directories(dir_ / "readonly");
    fs::permissions(dir_ / "readonly", fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                           fs::perms::others_read | fs::perms::others_exec);
    MakeClip(dir_ / "clip");
    fs::create_directories(dir_ / "open");
    fs::permissions(dir_ / "open", fs::perms::all);
  }
  TempDir dir_{"permission"};
};

TEST_F(LocalPermissionTest, TheCliNamesAClipItMayNotReadAndItsUser) {
  const auto result = RunAsNobody({BuiltBinary("client/endorecon"), "submit", (dir_ / "private").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("endorecon: " + (dir_ / "private").string()), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(": Permission denied (this command runs as user nobody)"), std::string::npos)
      << result.err;
  EXPECT_EQ(result.err.find("filesystem error"), std::string::npos) << result.err;
}

TEST_F(LocalPermissionTest, AReconstructionIntoAFolderItMayNotWriteIsRefusedBeforeItStarts) {
  const auto out = dir_ / "readonly" / "results";
  const auto result = RunAsNobody({BuiltBinary("worker/runtime/endorecon-worker"), "reconstruct",
                                   (dir_ / "clip").string(), "--out", out.string(), "--iterations", "2"});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("the output folder " + out.string() +
                            " cannot be made: " + (dir_ / "readonly").string() +
                            ": Permission denied (this command runs as user nobody)"),
            std::string::npos)
      << result.err;
  // Refused before the clip was loaded (its depth priors are logged as it loads).
  EXPECT_EQ(result.err.find("depth priors"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(out));
}

// prepare said "UNAVAILABLE: .../.clip.preparing-PID: cannot create"; to-dicom blamed FFmpeg.
TEST_F(LocalPermissionTest, PrepareAndToDicomNameTheFolderTheyMayNotWrite) {
  const std::string worker = BuiltBinary("worker/runtime/endorecon-worker");
  const std::string readonly = (dir_ / "readonly").string();
  const auto prepared =
      RunAsNobody({worker, "prepare", "--side-by-side", (dir_ / "clip" / "images").string(), "--rectified",
                   "--focal", "30", "--baseline", "1", "-o", readonly + "/prepared"});
  EXPECT_EQ(prepared.exit_code, 2) << prepared.err;
  EXPECT_NE(prepared.err.find("-o " + readonly + "/prepared: its parent folder " + readonly +
                              " cannot be written: " + readonly +
                              ": Permission denied (this command runs as user nobody)"),
            std::string::npos)
      << prepared.err;
  const auto converted =
      RunAsNobody({worker, "to-dicom", (dir_ / "clip" / "images").string(), "-o", readonly + "/video.dcm"});
  EXPECT_EQ(converted.exit_code, 2) << converted.err;
  EXPECT_NE(
      converted.err.find("-o " + readonly + "/video.dcm: its folder " + readonly + " cannot be written"),
      std::string::npos)
      << converted.err;
  EXPECT_EQ(converted.err.find("FFmpeg"), std::string::npos) << converted.err;
}

// A token file or CA the user may not read (root's, 0600) was "NOT_FOUND: cannot be read", exit 3:
// read as missing (found 2026-12-07).
TEST_F(LocalPermissionTest, ATokenFileOrCaItMayNotReadIsNotMissing) {
  const auto token = dir_ / "open" / "token";
  WriteBytes(token, "endorecon.0123456789abcdef.0123456789abcdef0123456789abcdef\n");
  fs::permissions(token, fs::perms::owner_read | fs::perms::owner_write);
  const auto listed = RunAsNobody({BuiltBinary("client/endorecon"), "--token-file", token.string(), "list"});
  EXPECT_EQ(listed.exit_code, 2) << listed.err;
  EXPECT_NE(listed.err.find("--token-file " + token.string() +
                            ": cannot be read: Permission denied (this command runs as user nobody)"),
            std::string::npos)
      << listed.err;
  const auto missing = RunAsNobody(
      {BuiltBinary("client/endorecon"), "--token-file", (dir_ / "open" / "none").string(), "list"});
  EXPECT_EQ(missing.exit_code, 3) << missing.err;
  EXPECT_NE(missing.err.find("none: no such file"), std::string::npos) << missing.err;
}

TEST_F(LocalPermissionTest, TheWorkerNamesAClipItMayNotRead) {
  const auto result =
      RunAsNobody({BuiltBinary("worker/runtime/endorecon-worker"), "reconstruct", (dir_ / "private").string(),
                   "--out", (dir_ / "open" / "results").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find((dir_ / "private").string()), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("Permission denied (this command runs as user nobody)"), std::string::npos)
      << result.err;
}

}  // namespace
}  // namespace endorecon::testing
