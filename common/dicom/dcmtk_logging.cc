#include "common/dicom/dcmtk_logging.h"

#include <dcmtk/oflog/appender.h>
#include <dcmtk/oflog/logger.h>
#include <dcmtk/oflog/oflog.h>
#include <dcmtk/oflog/spi/logevent.h>
#include <spdlog/spdlog.h>

#include <mutex>

namespace endorecon::dicom {
namespace {

// DCMTK's warnings and errors, into the process's log at debug level: each failure they tell of is
// reported by endorecon's own message, with its job and what to do. Printed by DCMTK as
// "E: Association Release Failed: 0006:0303 DUL Finite State Machine Error" on stderr, without a
// time or a job, they alarmed and could not be matched to anything (found 2026-12-05).
class SpdlogAppender : public dcmtk::log4cplus::Appender {
 public:
  ~SpdlogAppender() override { destructorImpl(); }
  void close() override {}

 protected:
  void append(const dcmtk::log4cplus::spi::InternalLoggingEvent& event) override {
    spdlog::debug("DCMTK {}: {}", event.getLoggerName().c_str(), event.getMessage().c_str());
  }
};

}  // namespace

void QuietDcmtkLogs() {
  static std::once_flag once;
  std::call_once(once, [] {
    OFLog::configure(OFLogger::WARN_LOG_LEVEL);
    dcmtk::log4cplus::Logger root = dcmtk::log4cplus::Logger::getRoot();
    root.removeAllAppenders();
    root.addAppender(dcmtk::log4cplus::SharedAppenderPtr(new SpdlogAppender()));
  });
}

}  // namespace endorecon::dicom
