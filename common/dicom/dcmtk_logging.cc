#include "common/dicom/dcmtk_logging.h"

#include <dcmtk/oflog/oflog.h>

#include <mutex>

namespace endorecon::dicom {

void QuietDcmtkLogs() {
  static std::once_flag once;
  std::call_once(once, [] { OFLog::configure(OFLogger::WARN_LOG_LEVEL); });
}

}  // namespace endorecon::dicom
