// The command-line flags of a DICOM recording's reading and of the DICOM results, registered the same
// way on `endorecon submit` and on `endorecon-worker reconstruct`.
#pragma once

#include "endorecon/v1/job.pb.h"

namespace CLI {
class App;
}

namespace endorecon {

// Registers --stereo --fps --endoscope on `cmd`, writing into `recording` (which must outlive parsing).
// --frames and --size, which a raw stereo recording takes too, are the caller's.
void AddRecordingFlags(CLI::App& cmd, v1::RecordingOptions& recording);

// Registers --dicom --patient-id --patient-name --study-uid on `cmd`, writing into `dicom` (which must
// outlive parsing).
void AddDicomResultFlags(CLI::App& cmd, v1::DicomOutputOptions& dicom);

}  // namespace endorecon
