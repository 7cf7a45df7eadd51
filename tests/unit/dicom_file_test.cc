#include "common/dicom_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "tests/unit/temp_dir.h"

namespace endorecon::dicom {
namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

TEST(DicomFileTest, TheMarkAtByte128OrTheNameMakesARecording) {
  testing::TempDir dir("dicom-file");
  Write(dir / "marked", std::string(128, '\0') + "DICM" + "rest");
  Write(dir / "named.DCM", "anything");
  Write(dir / "endo.mp4", std::string(200, 'x'));
  Write(dir / "short", "DICM");
  EXPECT_TRUE(IsDicomFile(dir / "marked"));
  EXPECT_FALSE(IsDicomFile(dir / "named.DCM"));
  EXPECT_FALSE(IsDicomFile(dir / "short"));
  EXPECT_TRUE(HasDicomExtension(dir / "named.DCM"));
  EXPECT_TRUE(HoldsDicom(dir / "marked"));
  EXPECT_TRUE(HoldsDicom(dir / "named.DCM"));
  EXPECT_FALSE(HoldsDicom(dir / "endo.mp4"));
  EXPECT_FALSE(HoldsDicom(dir / "short"));
  EXPECT_FALSE(HoldsDicom(dir / "missing"));
  // A folder holds a recording when a DICOM file lies directly in it.
  fs::create_directories(dir / "series" / "deeper");
  EXPECT_FALSE(HoldsDicom(dir / "series"));
  fs::copy_file(dir / "marked", dir / "series" / "deeper" / "1");
  EXPECT_FALSE(HoldsDicom(dir / "series"));
  fs::copy_file(dir / "marked", dir / "series" / "1");
  EXPECT_TRUE(HoldsDicom(dir / "series"));
  // A clip folder stays a clip with a recording kept beside its frames (it was reconstructed from
  // the recording, its poses, depth and masks ignored).
  Write(dir / "series" / "transforms.json", "{}");
  EXPECT_FALSE(HoldsDicom(dir / "series"));
}

}  // namespace
}  // namespace endorecon::dicom
