// The DICOM results: each instance passes dciodvfy (dicom3tools) without errors, joins the
// source's study with the patient copied, refers to the source series, and keeps its values.
#include "common/dicom/result_instances.h"

#include <dcmtk/dcmdata/dctk.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "common/dicom/recording.h"
#include "common/dicom/recording_writer.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "tests/unit/dciodvfy.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::dicom {
namespace {

using testing::DciodvfyErrors;
using testing::TempDir;

StudyContext SourceStudy(const TempDir& dir) {
  RecordingHeader header;
  header.study = NewStudyContext("P-77", "Doe^Jane", "", "");
  header.study.accession_number = "A-1";
  std::vector<cv::Mat> frames(2, cv::Mat(24, 32, CV_8UC3, cv::Scalar(10, 20, 30)));
  WriteEndoscopicFrames(frames, {0, 0.1}, false, header, dir / "source.dcm");
  return ReadRecording(dir / "source.dcm", {}).study;
}

DcmFileFormat Load(const std::filesystem::path& path) {
  DcmFileFormat file;
  EXPECT_TRUE(file.loadFile(path.c_str()).good()) << path;
  return file;
}

std::string Get(DcmFileFormat& file, const DcmTagKey& tag) {
  OFString value;
  file.getDataset()->findAndGetOFStringArray(tag, value);
  return value.c_str();
}

TEST(ResultInstancesTest, EachInstanceConformsAndJoinsTheSourceStudy) {
  TempDir dir;
  SeriesHeader header;
  header.study = SourceStudy(dir);
  header.uid_root = "1.2.826.0.1.3680043.10.999";
  header.frame_of_reference_uid = NewUid(header.uid_root);
  header.frame_times_s = {0, 0.04, 0.1};
  header.derivation_description = "test derivation";
  header.series_description = "rendered";
  std::vector<cv::Mat> rgb(3, cv::Mat(24, 32, CV_8UC3, cv::Scalar(0, 128, 255)));
  WriteColorFrames(dir / "rendered.dcm", header, rgb);
  header.series_number = 902;
  std::vector<std::vector<float>> depth(3, std::vector<float>(32 * 24, 57.25f));
  depth[1][5] = 129.5f;
  depth[2][7] = std::nanf("");
  WriteScalarFrames(dir / "depth.dcm", header, depth, 32, 24, {"MM", "depth in millimetres"});
  header.series_number = 904;
  std::string stl(84, '\0');
  WriteStlMesh(dir / "mesh.dcm", header, stl, "mm");

  for (const char* name : {"rendered.dcm", "depth.dcm", "mesh.dcm"}) {
    EXPECT_EQ(DciodvfyErrors(dir / name), "") << name;
    auto file = Load(dir / name);
    EXPECT_EQ(Get(file, DCM_StudyInstanceUID), header.study.study_instance_uid) << name;
    EXPECT_EQ(Get(file, DCM_PatientID), "P-77") << name;
    EXPECT_EQ(Get(file, DCM_PatientName), "Doe^Jane") << name;
    EXPECT_EQ(Get(file, DCM_AccessionNumber), "A-1") << name;
    EXPECT_EQ(Get(file, DCM_DerivationDescription), "test derivation") << name;
    EXPECT_EQ(Get(file, DCM_SOPInstanceUID).rfind(header.uid_root + ".", 0), 0u) << name;
    EXPECT_NE(Get(file, DCM_SeriesInstanceUID), header.study.source_series_uid) << name;
    DcmItem* referenced = nullptr;
    ASSERT_TRUE(file.getDataset()->findAndGetSequenceItem(DCM_ReferencedSeriesSequence, referenced, 0).good())
        << name;
    OFString series;
    referenced->findAndGetOFString(DCM_SeriesInstanceUID, series);
    EXPECT_EQ(std::string(series.c_str()), header.study.source_series_uid) << name;
  }

  auto rendered = Load(dir / "rendered.dcm");
  EXPECT_EQ(Get(rendered, DCM_SOPClassUID), UID_MultiframeTrueColorSecondaryCaptureImageStorage);
  EXPECT_EQ(Get(rendered, DCM_NumberOfFrames), "3");
  EXPECT_EQ(Get(rendered, DCM_FrameTimeVector), "0\\40\\60");

  auto depth_file = Load(dir / "depth.dcm");
  EXPECT_EQ(Get(depth_file, DCM_SOPClassUID), UID_MultiframeGrayscaleWordSecondaryCaptureImageStorage);
  EXPECT_EQ(Get(depth_file, DCM_RescaleType), "MM");
  const double slope = std::stod(Get(depth_file, DCM_RescaleSlope));
  const Uint16* stored = nullptr;
  ASSERT_TRUE(depth_file.getDataset()->findAndGetUint16Array(DCM_PixelData, stored).good());
  const std::size_t frame = 32 * 24;
  EXPECT_NEAR(stored[0] * slope, 57.25, slope);
  EXPECT_NEAR(stored[frame + 5] * slope, 129.5, slope);
  EXPECT_EQ(stored[2 * frame + 7], 0);  // not a number: no depth

  auto mesh = Load(dir / "mesh.dcm");
  EXPECT_EQ(Get(mesh, DCM_SOPClassUID), UID_EncapsulatedSTLStorage);
  EXPECT_EQ(Get(mesh, DCM_MIMETypeOfEncapsulatedDocument), "model/stl");
  EXPECT_EQ(Get(mesh, DCM_FrameOfReferenceUID), header.frame_of_reference_uid);
}

TEST(ResultInstancesTest, WithoutDicomInputTheResultsStartANewStudy) {
  TempDir dir;
  SeriesHeader header;
  header.study = NewStudyContext("", "", "", "");
  std::vector<cv::Mat> rgb(1, cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  WriteColorFrames(dir / "rendered.dcm", header, rgb);
  EXPECT_EQ(DciodvfyErrors(dir / "rendered.dcm"), "");
  auto file = Load(dir / "rendered.dcm");
  EXPECT_EQ(Get(file, DCM_StudyInstanceUID).rfind("2.25.", 0), 0u);
  // The default patient: the study UID's last 8 digits (a dot was among them; a short --study-uid
  // threw; found 2026-12-07).
  const std::string uid = Get(file, DCM_StudyInstanceUID);
  std::string digits = uid;
  digits.erase(std::remove(digits.begin(), digits.end(), '.'), digits.end());
  EXPECT_EQ(Get(file, DCM_PatientID), "ENDORECON-" + digits.substr(digits.size() - 8));
  // A new study's Study ID, the same digits (empty, a CD's DICOMDIR could not be made; found
  // 2026-12-07); a study joined keeps the PACS's own, so none is made up for it, and it needs its
  // patient (a made-up one split the study in the PACS; found 2026-12-07).
  EXPECT_EQ(Get(file, DCM_StudyID), digits.substr(digits.size() - 8));
  EXPECT_EQ(NewStudyContext("P-1", "", "1.2.3", "").study_id, "");
  EXPECT_THROW(NewStudyContext("", "", "1.2.3", ""), Error);
  DcmItem* referenced = nullptr;
  EXPECT_TRUE(file.getDataset()->findAndGetSequenceItem(DCM_ReferencedSeriesSequence, referenced, 0).bad());
}

TEST(ResultInstancesTest, UidsAreValidAndNew) {
  const std::string a = NewUid(""), b = NewUid("");
  EXPECT_NE(a, b);
  EXPECT_EQ(a.rfind("2.25.", 0), 0u);
  EXPECT_NO_THROW(CheckUid(a, "uid"));
  EXPECT_NO_THROW(CheckUid(NewUid("1.2.3"), "uid"));
  EXPECT_THROW(NewUid("1.02.3"), Error);
  EXPECT_THROW(NewUid("1.2.a"), Error);
  EXPECT_THROW(CheckUid("1..2", "uid"), Error);
  EXPECT_THROW(CheckUid(std::string(65, '1'), "uid"), Error);
}

}  // namespace
}  // namespace endorecon::dicom
