#include "common/file_read.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <iterator>
#include <string>

#include "common/error.h"
#include "common/secret_file.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(FileRead, OpensAFileAndSaysWhyOneCannotBeOpened) {
  testing::TempDir dir("file-read");
  testing::WriteBytes(dir / "a.json", "{}");
  std::ifstream in = OpenToRead(dir / "a.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "{}");
  // Under a file, which no folder is: the system's reason, not "cannot open the file" alone (as root,
  // which reads every file, this is a refusal a test can make).
  try {
    OpenToRead(dir / "a.json" / "b.png");
    FAIL() << "opened a path under a file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("a.json/b.png: cannot open the file (Not a directory)"),
              std::string::npos)
        << e.what();
  }
}

// A named pipe is refused by its kind, not opened: its open waits for a writer, and a server given
// one for --quotas or --tls-cert hung deaf to SIGTERM (found 2026-12-06). So are a folder and a
// device; a missing path is left to the open, or refused by RequireExistingFile as missing.
TEST(FileRead, APipeAFolderOrADeviceIsRefusedByItsKindBeforeItIsOpened) {
  testing::TempDir dir("file-read");
  ASSERT_EQ(::mkfifo((dir / "quotas.json").c_str(), 0600), 0);
  EXPECT_EQ(testing::ErrorFrom([&] { OpenToRead(dir / "quotas.json"); }),
            (dir / "quotas.json").string() + ": a named pipe (FIFO), not a file");
  EXPECT_EQ(testing::ErrorFrom([&] { RequireRegularFile(dir.path(), "calibration file"); }),
            dir.path().string() + ": a folder, not a calibration file");
  EXPECT_EQ(testing::ErrorFrom([] { RequireRegularFile("/dev/null"); }), "/dev/null: a device, not a file");
  EXPECT_NO_THROW(RequireRegularFile(dir / "missing"));
  try {
    RequireExistingFile(dir / "missing", "pose file");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_EQ(std::string(e.what()), (dir / "missing").string() + ": pose file does not exist");
  }
  // The secret and certificate files of TLS and tokens alike: a pipe's mode 0644 was reported as a
  // secret others may read; a file of other text as gRPC's "empty address list".
  ::chmod((dir / "quotas.json").c_str(), 0644);
  EXPECT_EQ(testing::ErrorFrom([&] { ReadSecretFile(dir / "quotas.json", "--token-file"); }),
            "--token-file " + (dir / "quotas.json").string() + ": a named pipe (FIFO), not a file");
  EXPECT_EQ(testing::ErrorFrom([&] { ReadPublicFile(dir / "quotas.json", "--ca"); }),
            "--ca " + (dir / "quotas.json").string() + ": a named pipe (FIFO), not a file");
  EXPECT_EQ(testing::ErrorFrom([&] { ReadPublicFile(dir.path(), "--ca"); }),
            "--ca " + dir.path().string() + ": a folder, not a file");
  testing::WriteBytes(dir / "hello.crt", "hello\n");
  EXPECT_EQ(testing::ErrorFrom([&] { ReadPublicFile(dir / "hello.crt", "--ca"); }),
            "--ca " + (dir / "hello.crt").string() +
                ": holds no PEM certificate (no \"-----BEGIN CERTIFICATE-----\" line)");
}

}  // namespace
}  // namespace endorecon
