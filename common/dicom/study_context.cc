#include "common/dicom/study_context.h"

#include <dcmtk/dcmdata/dctk.h>

#include "common/dicom/dataset_access.h"
#include "common/dicom/uid.h"
#include "common/dicom_values.h"
#include "common/error.h"

namespace endorecon::dicom {
namespace {

std::string Get(DcmItem& item, const DcmTagKey& tag) { return FindString(item, tag).value_or(""); }

}  // namespace

StudyContext ReadStudyContext(DcmItem& dataset, const std::string& where) {
  StudyContext study;
  study.specific_character_set = Get(dataset, DCM_SpecificCharacterSet);
  study.patient_name = Get(dataset, DCM_PatientName);
  study.patient_id = Get(dataset, DCM_PatientID);
  study.issuer_of_patient_id = Get(dataset, DCM_IssuerOfPatientID);
  study.patient_birth_date = Get(dataset, DCM_PatientBirthDate);
  study.patient_sex = Get(dataset, DCM_PatientSex);
  study.study_instance_uid = Get(dataset, DCM_StudyInstanceUID);
  study.study_date = Get(dataset, DCM_StudyDate);
  study.study_time = Get(dataset, DCM_StudyTime);
  study.study_id = Get(dataset, DCM_StudyID);
  study.accession_number = Get(dataset, DCM_AccessionNumber);
  study.referring_physician_name = Get(dataset, DCM_ReferringPhysicianName);
  study.study_description = Get(dataset, DCM_StudyDescription);
  study.source_series_uid = Get(dataset, DCM_SeriesInstanceUID);
  const SourceInstance source{Get(dataset, DCM_SOPClassUID), Get(dataset, DCM_SOPInstanceUID)};
  if (study.study_instance_uid.empty()) FailInvalid(where + ": no Study Instance UID (0020,000D)");
  if (source.sop_instance_uid.empty()) FailInvalid(where + ": no SOP Instance UID (0008,0018)");
  study.source_instances.push_back(source);
  return study;
}

StudyContext NewStudyContext(const std::string& patient_id, const std::string& patient_name,
                             const std::string& study_uid, const std::string& uid_root) {
  StudyContext study;
  if (!study_uid.empty()) CheckUid(study_uid, "--study-uid");
  CheckPatientId(patient_id, "--patient-id");
  CheckPatientName(patient_name, "--patient-name");
  CheckStudyJoin(patient_id, study_uid);
  study.study_instance_uid = study_uid.empty() ? NewUid(uid_root) : study_uid;
  study.specific_character_set = "ISO_IR 192";  // UTF-8: names typed on a command line
  // The default: the UID's last 8 digits, its dots left out (it took the last 8 characters, a dot
  // among them, and threw on a --study-uid shorter than 8; found 2026-12-07).
  std::string digits;
  for (auto c = study.study_instance_uid.rbegin(); c != study.study_instance_uid.rend() && digits.size() < 8;
       ++c)
    if (*c != '.') digits.insert(digits.begin(), *c);
  study.patient_id = patient_id.empty() ? "ENDORECON-" + digits : patient_id;
  // A new study's Study ID, the same digits: empty, a CD's DICOMDIR could not be made of it (dcmmkdir:
  // "required attribute StudyID empty"; found 2026-12-07). A study joined keeps the PACS's own.
  if (study_uid.empty()) study.study_id = digits;
  study.patient_name = patient_name;
  OFString date, time;
  DcmDate::getCurrentDate(date);
  DcmTime::getCurrentTime(time);
  study.study_date = date.c_str();
  study.study_time = time.c_str();
  return study;
}

void WriteStudyModules(const StudyContext& study, DcmItem& dataset) {
  if (!study.specific_character_set.empty()) {
    Put(dataset, DCM_SpecificCharacterSet, study.specific_character_set);
  }
  Put(dataset, DCM_PatientName, study.patient_name);
  Put(dataset, DCM_PatientID, study.patient_id);
  if (!study.issuer_of_patient_id.empty()) Put(dataset, DCM_IssuerOfPatientID, study.issuer_of_patient_id);
  Put(dataset, DCM_PatientBirthDate, study.patient_birth_date);
  Put(dataset, DCM_PatientSex, study.patient_sex);
  Put(dataset, DCM_StudyInstanceUID, study.study_instance_uid);
  Put(dataset, DCM_StudyDate, study.study_date);
  Put(dataset, DCM_StudyTime, study.study_time);
  Put(dataset, DCM_StudyID, study.study_id);
  Put(dataset, DCM_AccessionNumber, study.accession_number);
  Put(dataset, DCM_ReferringPhysicianName, study.referring_physician_name);
  if (!study.study_description.empty()) Put(dataset, DCM_StudyDescription, study.study_description);
}

}  // namespace endorecon::dicom
