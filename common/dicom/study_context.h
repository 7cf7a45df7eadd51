// The patient and study a recording belongs to, and the source instances derived results refer
// to. Read from a recording's dataset, or made for a new study when the input was not DICOM.
// These values identify a patient: keep them out of logs and error messages.
#pragma once

#include <string>
#include <vector>

class DcmItem;

namespace endorecon::dicom {

struct SourceInstance {
  std::string sop_class_uid;
  std::string sop_instance_uid;
};

struct StudyContext {
  // Patient module (copied as it is, with the character set its names are in).
  std::string specific_character_set;
  std::string patient_name, patient_id, issuer_of_patient_id, patient_birth_date, patient_sex;
  // General Study module.
  std::string study_instance_uid, study_date, study_time, study_id, accession_number;
  std::string referring_physician_name, study_description;
  // The series the recording came from (empty without DICOM input) and its instances.
  std::string source_series_uid;
  std::vector<SourceInstance> source_instances;
};

// The patient, study and source of `dataset`. Throws InvalidArgument naming `where` when it has no
// Study Instance UID or SOP Instance UID.
StudyContext ReadStudyContext(DcmItem& dataset, const std::string& where);

// A new study for results of an input that was not DICOM: the given patient (empty: anonymous,
// Patient ID "ENDORECON-" and the study's first digits) and study UID (empty: a new one), dated now.
StudyContext NewStudyContext(const std::string& patient_id, const std::string& patient_name,
                             const std::string& study_uid, const std::string& uid_root);

// Writes the Patient and General Study modules of `study` into `dataset`.
void WriteStudyModules(const StudyContext& study, DcmItem& dataset);

}  // namespace endorecon::dicom
