// Retrieval of a study (or one series of it) from a PACS: C-GET straight into a folder, or C-MOVE
// to a storage SCP (storage_scp.h) that the PACS connects back to.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/dicom/peer.h"

namespace endorecon::dicom {

struct RetrieveRequest {
  Peer peer;
  std::string calling_ae_title = "ENDORECON";
  std::string study_uid;
  std::string series_uid;  // empty: the whole study
  int timeout_s = 60;      // connect, association and each response
};

// Called after each instance received: instances and bytes so far.
using RetrieveProgress = std::function<void(int instances, std::int64_t bytes)>;

// C-GET of the study (or series) into `out_dir` (created), one file per instance. Returns the
// number of instances received. Throws Error(kUnavailable) when the PACS cannot be reached (it may be
// back later), kFailedPrecondition when it rejects the association, does not offer C-GET, refuses it
// with a status or aborts it (say so: C-MOVE may work), kNotFound when it holds nothing that matches,
// kDataLoss when some sub-operations failed.
int GetStudy(const RetrieveRequest& request, const std::filesystem::path& out_dir,
             const RetrieveProgress& progress);

// What a study holds, by series, from a C-FIND at IMAGE level (Study Root): the series whose every
// instance is of a class endorecon takes (storage_classes.h), and the instances of other classes
// (a CT, a report), counted by class name. A PACS fails a whole-study retrieval when one object has
// no context, so a study holding others is retrieved series by series. Throws Error(kUnavailable)
// when the PACS cannot be reached, kFailedPrecondition when it refuses the association or fails the
// query.
struct StudyContents {
  std::vector<std::string> recording_series;  // in the order the PACS listed them
  std::map<std::string, int> other_classes;   // class name -> instances
  int other_series = 0;                       // series left out (holding any other class)
};
StudyContents FindStudyContents(const RetrieveRequest& request);

// C-MOVE of the study (or series) to `destination_ae` (the PACS must know that AE's address).
// Returns the number of instances the PACS reports moved. Errors as GetStudy.
int MoveStudy(const RetrieveRequest& request, const std::string& destination_ae);

}  // namespace endorecon::dicom
