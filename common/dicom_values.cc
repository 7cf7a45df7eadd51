#include "common/dicom_values.h"

#include <algorithm>
#include <string_view>
#include <vector>

#include "common/error.h"
#include "common/safe_path.h"

namespace endorecon::dicom {
namespace {

// PS3.5 6.2: LO and each PN component group hold at most 64 characters.
constexpr std::size_t kMostCharacters = 64;

// Characters, not bytes: UTF-8 continuation bytes do not count (the values are written as UTF-8).
std::size_t Characters(std::string_view text) {
  return static_cast<std::size_t>(std::count_if(
      text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

void CheckCharacters(std::string_view text, const std::string& what) {
  // The values are written as UTF-8 (ISO_IR 192): Latin-1 bytes from a terminal went into the files
  // as they were, and a PACS dropped the letters ("Müller" became "Mller"); to the server they were
  // "INTERNAL: submit (checked before the upload): " with no reason (found 2026-12-07).
  if (!IsUtf8(text)) {
    FailInvalid(what +
                " is not UTF-8 text (a byte of another encoding, such as Latin-1's 0xFC for 'ü'): "
                "DICOM values are written in UTF-8; type it in a UTF-8 terminal or convert it (iconv -f "
                "latin1 -t utf-8)");
  }
  if (text.find('\\') != std::string_view::npos)
    FailInvalid(what + " holds a backslash, which separates values in DICOM; give one value");
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 && c != 0x1b)  // ESC starts a character-set escape
      FailInvalid(what + " holds a control character");
  }
}

std::vector<std::string_view> Split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const std::size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return parts;
    start = end + 1;
  }
}

}  // namespace

void CheckPatientId(const std::string& id, const std::string& what) {
  CheckCharacters(id, what);
  if (Characters(id) > kMostCharacters) {
    FailInvalid(what + " holds " + std::to_string(Characters(id)) +
                " characters; a DICOM Patient ID (LO) holds at most 64");
  }
}

void CheckPatientName(const std::string& name, const std::string& what) {
  CheckCharacters(name, what);
  const auto groups = Split(name, '=');
  if (groups.size() > 3) {
    FailInvalid(
        what + " has " + std::to_string(groups.size()) +
        " component groups ('='); a DICOM name (PN) has at most 3: alphabetic, ideographic, phonetic");
  }
  for (const std::string_view group : groups) {
    if (Characters(group) > kMostCharacters) {
      FailInvalid(what + " has a component group of " + std::to_string(Characters(group)) +
                  " characters; a DICOM name (PN) allows 64 per group");
    }
    if (Split(group, '^').size() > 5) {
      FailInvalid(what +
                  " has more than 5 components ('^'); a DICOM name (PN) is "
                  "family^given^middle^prefix^suffix");
    }
  }
}

void CheckStudyJoin(const std::string& patient_id, const std::string& study_uid) {
  if (study_uid.empty() || !patient_id.empty()) return;
  FailInvalid(
      "--study-uid joins the results to an existing study: give that study's patient too (--patient-id, "
      "and --patient-name), or the PACS files the study under two patients, its own and a made-up one");
}

void CheckDicomResultFlags(bool dicom, bool recording, const std::string& patient_id,
                           const std::string& patient_name, const std::string& study_uid) {
  CheckPatientId(patient_id, "--patient-id");
  CheckPatientName(patient_name, "--patient-name");
  if (patient_id.empty() && patient_name.empty() && study_uid.empty()) return;
  if (recording) {
    FailInvalid(
        "--patient-id, --patient-name and --study-uid name the patient and study of results made "
        "from a clip; a DICOM recording's results keep its own patient and study");
  }
  if (!dicom) FailInvalid("--patient-id, --patient-name and --study-uid go with --dicom (DICOM results)");
  CheckStudyJoin(patient_id, study_uid);
}

}  // namespace endorecon::dicom
