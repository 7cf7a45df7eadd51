#include "common/dicom_values.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "common/error.h"

namespace endorecon::dicom {
namespace {

std::string Refusal(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "";
}

TEST(DicomValuesTest, APatientIdIsOneValueOfAtMost64Characters) {
  EXPECT_EQ(Refusal([] { CheckPatientId("PAT-4711", "--patient-id"); }), "");
  EXPECT_EQ(Refusal([] { CheckPatientId(std::string(64, 'Y'), "--patient-id"); }), "");
  // 64 characters of two bytes each are 64 characters.
  std::string umlauts;
  for (int i = 0; i < 64; ++i) umlauts += "\xc3\xbc";
  EXPECT_EQ(Refusal([&] { CheckPatientId(umlauts, "--patient-id"); }), "");
  const std::string message = Refusal([] { CheckPatientId(std::string(80, 'Y'), "--patient-id"); });
  EXPECT_NE(message.find("--patient-id holds 80 characters; a DICOM Patient ID (LO) holds at most 64"),
            std::string::npos)
      << message;
  EXPECT_EQ(message.find("YYYY"), std::string::npos) << "the value identifies a patient: " << message;
  EXPECT_NE(Refusal([] { CheckPatientId("A\\B", "--patient-id"); }).find("backslash"), std::string::npos);
  EXPECT_NE(Refusal([] { CheckPatientId("A\nB", "--patient-id"); }).find("control character"),
            std::string::npos);
}

// Latin-1 bytes were written as they were under ISO_IR 192, and a PACS dropped the letter ("Müller"
// became "Mller"); the server's request failed with no reason (found 2026-12-07).
TEST(DicomValuesTest, ValuesAreUtf8) {
  EXPECT_EQ(Refusal([] { CheckPatientName("M\xc3\xbcller^Jos\xc3\xa9", "--patient-name"); }), "");
  const std::string message = Refusal([] { CheckPatientName("M\xfcller^Jos\xe9", "--patient-name"); });
  EXPECT_NE(message.find("--patient-name is not UTF-8 text"), std::string::npos) << message;
  EXPECT_NE(Refusal([] {
              CheckPatientId(
                  "P\xfc"
                  "1",
                  "--patient-id");
            }).find("--patient-id is not UTF-8"),
            std::string::npos);
}

// Results joining a study under a made-up patient were filed by the PACS under two patients (found
// 2026-12-07): a study joined needs its patient.
TEST(DicomValuesTest, AStudyJoinedNamesItsPatient) {
  EXPECT_EQ(Refusal([] { CheckStudyJoin("", ""); }), "");
  EXPECT_EQ(Refusal([] { CheckStudyJoin("PAT-4711", "1.2.3"); }), "");
  EXPECT_NE(Refusal([] { CheckStudyJoin("", "1.2.3"); }).find("give that study's patient too (--patient-id"),
            std::string::npos);
  EXPECT_NE(Refusal([] { CheckDicomResultFlags(true, false, "", "", "1.2.3"); }).find("--study-uid joins"),
            std::string::npos);
}

TEST(DicomValuesTest, APatientNameIsOnePersonName) {
  for (const std::string good : {"", "Doe^Jane", "Doe^Jane^Q^Dr^III", "Yamada^Tarou=山田^太郎=やまだ^たろう"})
    EXPECT_EQ(Refusal([&] { CheckPatientName(good, "--patient-name"); }), "") << good;
  EXPECT_NE(Refusal([] { CheckPatientName("A^B\\C^D", "--patient-name"); }).find("backslash"),
            std::string::npos);
  EXPECT_NE(Refusal([] { CheckPatientName("a=b=c=d", "--patient-name"); }).find("4 component groups"),
            std::string::npos);
  EXPECT_NE(Refusal([] { CheckPatientName("a^b^c^d^e^f", "--patient-name"); }).find("more than 5 components"),
            std::string::npos);
  EXPECT_NE(Refusal([] { CheckPatientName(std::string(65, 'N'), "--patient-name"); }).find("65 characters"),
            std::string::npos);
}

TEST(DicomValuesTest, PatientFlagsGoWithDicomResultsOfAClip) {
  EXPECT_EQ(Refusal([] { CheckDicomResultFlags(true, false, "P1", "Doe^Jane", "1.2.3"); }), "");
  EXPECT_EQ(Refusal([] { CheckDicomResultFlags(false, true, "", "", ""); }), "");
  EXPECT_NE(Refusal([] { CheckDicomResultFlags(false, false, "P1", "", ""); }).find("go with --dicom"),
            std::string::npos);
  EXPECT_NE(Refusal([] {
              CheckDicomResultFlags(true, true, "", "Doe^Jane", "");
            }).find("a DICOM recording's results keep its own patient and study"),
            std::string::npos);
}

}  // namespace
}  // namespace endorecon::dicom
