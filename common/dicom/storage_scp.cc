#include "common/dicom/storage_scp.h"

#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmnet/dstorscp.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "common/dicom/dataset_access.h"
#include "common/dicom/dcmtk_logging.h"
#include "common/dicom/peer.h"
#include "common/dicom/storage_classes.h"
#include "common/dicom/uid.h"
#include "common/error.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;

class StorageScp::Scp : public DcmStorageSCP {
 public:
  Scp(const StorageScpSettings& settings, OnStored on_stored, Awaits awaits)
      : settings_(settings), on_stored_(std::move(on_stored)), awaits_(std::move(awaits)) {}
  std::atomic<bool> stop{false};

 protected:
  OFBool stopAfterConnectionTimeout() override { return stop.load(); }
  OFBool stopAfterCurrentAssociation() override { return stop.load(); }
  // DCMTK 3.6.7 neither binds one interface nor tells the check which host calls, so the SCP
  // admits callers by AE title: the PACS configured on the server.
  OFBool checkCallingAETitleAccepted(const OFString& calling) override {
    const auto& allowed = settings_.calling_ae_titles;
    const bool accepted =
        allowed.empty() || std::find(allowed.begin(), allowed.end(), calling.c_str()) != allowed.end();
    if (!accepted)
      spdlog::warn("storage SCP: refused an association from AE '{}' (not a configured PACS)",
                   calling.c_str());
    return accepted;
  }

  // Only this SCP's own AE title is answered (any title was).
  OFBool checkCalledAETitleAccepted(const OFString& called) override {
    std::string title = called.c_str();
    while (!title.empty() && title.back() == ' ') title.pop_back();
    const bool accepted = title == settings_.ae_title;
    if (!accepted)
      spdlog::warn("storage SCP: refused an association called '{}' (this SCP is '{}')", title,
                   settings_.ae_title);
    return accepted;
  }

  Uint16 checkAndProcessSTORERequest(const T_DIMSE_C_StoreRQ& request, DcmFileFormat& file) override {
    DcmDataset& data = *file.getDataset();
    const std::string study = FindString(data, DCM_StudyInstanceUID).value_or("");
    const std::string series = FindString(data, DCM_SeriesInstanceUID).value_or("");
    const std::string sop = request.AffectedSOPInstanceUID;
    // Whether a retrieval awaits the study is asked first: an endorecon result sent unasked was
    // answered Success (found 2026-12-07).
    if (!awaits_ || !awaits_(study)) {
      spdlog::warn("storage SCP: refused an instance of a study no retrieval awaits");
      return kRefusedNotAuthorized;
    }
    if (IsEndoreconResult(data)) return STATUS_Success;  // taken, not kept (storage_classes.h)
    try {
      CheckUid(study, "Study Instance UID");
      CheckUid(series, "Series Instance UID");
      CheckUid(sop, "SOP Instance UID");
    } catch (const Error& e) {
      spdlog::warn("storage SCP: refused an instance: {}", e.what());
      return STATUS_STORE_Error_CannotUnderstand;
    }
    const fs::path folder = settings_.folder / study / series;
    const fs::path target = folder / (sop + ".dcm");
    const fs::path partial = folder / (sop + ".dcm.part");
    std::error_code error;
    fs::create_directories(folder, error);
    if (error || file.saveFile(partial.c_str(), data.getOriginalXfer()).bad()) {
      return STATUS_STORE_Refused_OutOfResources;
    }
    fs::rename(partial, target, error);
    if (error) return STATUS_STORE_Refused_OutOfResources;
    if (on_stored_) on_stored_(study, target, static_cast<std::int64_t>(fs::file_size(target, error)));
    return STATUS_Success;
  }

 private:
  // C-STORE status "Refused: Not Authorized" (PS3.4 GG.4-1; DCMTK 3.6.7 names no constant for it).
  static constexpr Uint16 kRefusedNotAuthorized = 0x0124;

  StorageScpSettings settings_;
  OnStored on_stored_;
  Awaits awaits_;
};

StorageScp::StorageScp(const StorageScpSettings& settings, OnStored on_stored, Awaits awaits)
    : settings_(settings), scp_(std::make_unique<Scp>(settings, std::move(on_stored), std::move(awaits))) {
  QuietDcmtkLogs();
  CheckAeTitle(settings.ae_title, "the storage SCP's AE title");
  fs::create_directories(settings.folder);
  scp_->setAETitle(settings.ae_title.c_str());
  scp_->setPort(static_cast<Uint16>(settings.port));
  scp_->setConnectionBlockingMode(DUL_NOBLOCK);
  scp_->setConnectionTimeout(1);
  scp_->setDIMSEBlockingMode(DIMSE_NONBLOCKING);
  scp_->setDIMSETimeout(60);
  scp_->setACSETimeout(30);
  scp_->setHostLookupEnabled(OFFalse);
  // DcmStorageSCP already offers Verification; a second context for it would make the profile invalid.
  for (const auto& storage : RecordingStorageClasses()) {
    OFList<OFString> syntaxes;
    for (const auto& ts : storage.transfer_syntaxes) syntaxes.push_back(ts.c_str());
    if (storage.transfer_syntaxes.front() != UID_LittleEndianExplicitTransferSyntax) {
      syntaxes.push_back(UID_LittleEndianExplicitTransferSyntax);
      syntaxes.push_back(UID_LittleEndianImplicitTransferSyntax);
    }
    scp_->addPresentationContext(storage.sop_class.c_str(), syntaxes);
  }
  const OFCondition status = scp_->openListenPort();
  if (status.bad()) {
    Fail(ErrorCode::kUnavailable,
         "storage SCP cannot listen on port " + std::to_string(settings.port) + ": " + status.text());
  }
  thread_ = std::thread([this] {
    const OFCondition result = scp_->acceptAssociations();
    if (result.bad() && result != NET_EC_StopAfterConnectionTimeout &&
        result != NET_EC_StopAfterAssociation) {
      spdlog::error("storage SCP stopped: {}", result.text());
    }
  });
}

StorageScp::~StorageScp() {
  scp_->stop = true;
  if (thread_.joinable()) thread_.join();
}

}  // namespace endorecon::dicom
