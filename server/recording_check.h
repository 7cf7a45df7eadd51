// A DICOM recording a job names, checked against the job's recording options from its files'
// headers before the job is queued (common/dicom/recording_header.h): a --frames window past the
// recording's end, a --size of another shape, a --stereo layout its series do not fit, a file that is
// no recording the worker could read. Said to the submitter at once (INVALID_ARGUMENT), or for a
// recording retrieved from a PACS as the job's failure, instead of by a worker after the queue.
#pragma once

#include <string>

#include "endorecon/v1/files.pb.h"
#include "endorecon/v1/job_service.pb.h"
#include "server/blob_store.h"

namespace endorecon::server {

// Does nothing when `clip` is no DICOM recording as the worker will see it (dicom::HoldsDicom of the
// files directly in its folder, as the worker lays them out) or a blob it names there is missing (the
// caller's own check names that). Throws Error(kInvalidArgument) naming files by their paths in `clip`.
void CheckRecording(const v1::Manifest& clip, const v1::RecordingOptions& options, const BlobStore& blobs);

}  // namespace endorecon::server
