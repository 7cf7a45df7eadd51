// Retrieval of a study (or one series of it) from a PACS: C-GET straight into a folder, or C-MOVE
// to a storage SCP (storage_scp.h) that the PACS connects back to.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

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
// number of instances received. Throws Error(kUnavailable) when the PACS cannot be reached,
// rejects the association or refuses C-GET (say so: C-MOVE may work), kNotFound when it holds
// nothing that matches, kDataLoss when some sub-operations failed.
int GetStudy(const RetrieveRequest& request, const std::filesystem::path& out_dir,
             const RetrieveProgress& progress);

// C-MOVE of the study (or series) to `destination_ae` (the PACS must know that AE's address).
// Returns the number of instances the PACS reports moved. Errors as GetStudy.
int MoveStudy(const RetrieveRequest& request, const std::string& destination_ae);

}  // namespace endorecon::dicom
