// DCMTK logs through its own logger (oflog) to stderr at INFO by default: a line per association
// and message. endorecon keeps its warnings and errors only, so its own logs stay readable.
#pragma once

namespace endorecon::dicom {

// Sets DCMTK's log level to WARN, once per process; every network entry point calls it.
void QuietDcmtkLogs();

}  // namespace endorecon::dicom
