// Patient values typed by a user (--patient-id, --patient-name) checked against their DICOM value
// representations before anything is written or uploaded, without DCMTK, so the CLI, the server and
// the worker refuse them alike. Messages never repeat the values: they identify a patient.
#pragma once

#include <string>

namespace endorecon::dicom {

// Patient ID (LO): at most 64 characters, no backslash (it separates values), no control
// characters. Throws FailInvalid naming `what` (the flag or field).
void CheckPatientId(const std::string& id, const std::string& what);

// Patient's Name (PN): one value (no backslash), at most three component groups separated by '='
// each of at most 64 characters and five components separated by '^', no control characters.
void CheckPatientName(const std::string& name, const std::string& what);

// Throws FailInvalid when `study_uid` (results joining an existing study) comes without the study's
// patient (`patient_id` empty): the results named a made-up patient, and a PACS filed the one study
// under two patients (found 2026-12-07).
void CheckStudyJoin(const std::string& patient_id, const std::string& study_uid);

// The DICOM result flags of `endorecon submit` and `endorecon-worker reconstruct`, checked before
// anything is uploaded or trained: the patient values (above), and that --patient-id, --patient-name
// and --study-uid come with --dicom and not with a DICOM recording (`recording`), whose results keep
// its own patient and study (they were ignored without a word).
void CheckDicomResultFlags(bool dicom, bool recording, const std::string& patient_id,
                           const std::string& patient_name, const std::string& study_uid);

}  // namespace endorecon::dicom
