// DCMTK logs through its own logger (oflog) to stderr: a line per association and message at INFO
// by default, and errors ("E: ...") that endorecon reports again in its own words. Its warnings and
// errors go to the process's log (spdlog) at debug level instead.
#pragma once

namespace endorecon::dicom {

// Sets DCMTK's log level to WARN and routes what it logs to spdlog::debug, once per process; every
// network entry point calls it.
void QuietDcmtkLogs();

}  // namespace endorecon::dicom
