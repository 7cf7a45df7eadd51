// dicom::SaveFile: the bytes DCMTK encodes reach the file, or the write is an error.
#include "common/dicom/file_save.h"

#include <dcmtk/dcmdata/dctk.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::dicom {
namespace {

DcmFileFormat SmallInstance() {
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  data.putAndInsertString(DCM_SOPClassUID, UID_SecondaryCaptureImageStorage);
  data.putAndInsertString(DCM_SOPInstanceUID, "2.25.1");
  data.putAndInsertString(DCM_PatientName, "Doe^Jane");
  return file;
}

TEST(DicomFileSaveTest, TheFileReadsBackWithItsMetaHeader) {
  testing::TempDir dir("file-save");
  DcmFileFormat file = SmallInstance();
  SaveFile(file, dir / "sub" / "a.dcm", EXS_LittleEndianExplicit);
  DcmFileFormat read;
  ASSERT_TRUE(read.loadFile((dir / "sub" / "a.dcm").c_str()).good());
  OFString name, syntax;
  EXPECT_TRUE(read.getDataset()->findAndGetOFString(DCM_PatientName, name).good());
  EXPECT_EQ(std::string(name.c_str()), "Doe^Jane");
  EXPECT_TRUE(read.getMetaInfo()->findAndGetOFString(DCM_TransferSyntaxUID, syntax).good());
  EXPECT_EQ(std::string(syntax.c_str()), UID_LittleEndianExplicitTransferSyntax);
  EXPECT_FALSE(std::filesystem::exists(dir / "sub" / "a.dcm.tmp"));
}

// DCMTK's saveFile reported success for -o /dev/full and for a file cut at a size limit (found
// 2026-12-05); a device or a folder is no file to write an instance to.
TEST(DicomFileSaveTest, ADeviceOrAFolderIsRefused) {
  testing::TempDir dir("file-save");
  DcmFileFormat file = SmallInstance();
  std::string message = testing::ErrorFrom([&] { SaveFile(file, "/dev/null", EXS_LittleEndianExplicit); });
  EXPECT_NE(message.find("/dev/null: not a regular file"), std::string::npos) << message;
  message = testing::ErrorFrom([&] { SaveFile(file, dir.path(), EXS_LittleEndianExplicit); });
  EXPECT_NE(message.find("not a regular file"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon::dicom
