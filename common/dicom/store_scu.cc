#include "common/dicom/store_scu.h"

#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmnet/assoc.h>
#include <dcmtk/dcmnet/dimse.h>
#include <dcmtk/dcmnet/diutil.h>

#include <map>
#include <memory>

#include "common/dicom/dataset_access.h"
#include "common/dicom/dcmtk_logging.h"
#include "common/error.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;
namespace {

struct FileInfo {
  std::string sop_class, sop_instance, transfer_syntax;
};

FileInfo Inspect(const fs::path& path) {
  DcmFileFormat file;
  const OFCondition status = file.loadFile(path.c_str(), EXS_Unknown, EGL_noChange, 1024);
  if (status.bad()) FailInvalid(path.string() + ": not a readable DICOM file: " + status.text());
  FileInfo info;
  info.sop_class = FindString(*file.getDataset(), DCM_SOPClassUID).value_or("");
  info.sop_instance = FindString(*file.getDataset(), DCM_SOPInstanceUID).value_or("");
  info.transfer_syntax = FindString(*file.getMetaInfo(), DCM_TransferSyntaxUID).value_or("");
  if (info.sop_class.empty() || info.sop_instance.empty()) {
    FailInvalid(path.string() + ": no SOP Class UID or SOP Instance UID");
  }
  return info;
}

bool Uncompressed(const std::string& ts) {
  return ts == UID_LittleEndianExplicitTransferSyntax || ts == UID_LittleEndianImplicitTransferSyntax ||
         ts == UID_BigEndianExplicitTransferSyntax;
}

// Owns the network and the association; releases (or aborts) and frees them on every path.
class Association {
 public:
  Association() = default;
  // Negotiates; the destructor cleans up after a failure here too.
  void Open(const Peer& peer, const StoreSettings& settings, const std::vector<FileInfo>& infos) {
    dcmConnectionTimeout.set(settings.timeout_s);
    Check(ASC_initializeNetwork(NET_REQUESTOR, 0, settings.timeout_s, &network_), "network");
    T_ASC_Parameters* params = nullptr;
    Check(ASC_createAssociationParameters(&params, ASC_DEFAULTMAXPDU), "parameters");
    ASC_setAPTitles(params, settings.calling_ae_title.c_str(), peer.ae_title.c_str(), nullptr);
    const std::string address = peer.host + ":" + std::to_string(peer.port);
    ASC_setPresentationAddresses(params, "localhost", address.c_str());
    std::map<std::string, std::vector<std::string>> syntaxes;  // SOP class -> compressed syntaxes
    for (const auto& info : infos) {
      auto& list = syntaxes[info.sop_class];
      if (!Uncompressed(info.transfer_syntax) &&
          std::find(list.begin(), list.end(), info.transfer_syntax) == list.end()) {
        list.push_back(info.transfer_syntax);
      }
    }
    int id = 1;
    for (const auto& [sop_class, compressed] : syntaxes) {
      for (const auto& ts : compressed) {
        const char* one[] = {ts.c_str()};
        Add(params, id, sop_class, one, 1);
      }
      const char* plain[] = {UID_LittleEndianExplicitTransferSyntax, UID_LittleEndianImplicitTransferSyntax};
      Add(params, id, sop_class, plain, 2);
    }
    const std::string where = "association with " + PeerText(peer);
    const OFCondition status = ASC_requestAssociation(network_, params, &association_);
    if (status == DUL_ASSOCIATIONREJECTED) {
      T_ASC_RejectParameters reject;
      ASC_getRejectParameters(params, &reject);
      OFString reason;
      ASC_printRejectParameters(reason, &reject);
      for (auto& c : reason) c = c == '\n' ? ';' : c;
      Fail(ErrorCode::kUnavailable, where + " rejected: " + reason.c_str());
    }
    if (status.bad()) {
      if (association_ == nullptr) ASC_destroyAssociationParameters(&params);
      Fail(ErrorCode::kUnavailable, where + " failed: " + status.text());
    }
    if (ASC_countAcceptedPresentationContexts(association_->params) == 0) {
      // Which kinds of object: a retry of the one object a PACS would not store (an Encapsulated STL)
      // ended "accepted none of the presentation contexts", which named nothing (found 2026-12-07).
      std::string classes;
      for (const auto& entry : syntaxes) classes += (classes.empty() ? "" : ", ") + UidName(entry.first);
      Fail(ErrorCode::kUnavailable, where + ": the peer accepted none of the presentation contexts, for " +
                                        classes + ": it stores no object of that kind (its configuration)");
    }
    established_ = true;
  }
  ~Association() {
    if (association_ != nullptr) {
      if (established_ && ASC_releaseAssociation(association_).bad()) ASC_abortAssociation(association_);
      ASC_destroyAssociation(&association_);
    }
    if (network_ != nullptr) ASC_dropNetwork(&network_);
  }
  Association(const Association&) = delete;
  Association& operator=(const Association&) = delete;

  T_ASC_Association* get() { return association_; }

 private:
  // Presentation context IDs are the odd numbers 1 to 255.
  void Add(T_ASC_Parameters* params, int& id, const std::string& sop_class, const char** list, int count) {
    if (id > 255) Fail(ErrorCode::kResourceExhausted, "more than 128 presentation contexts needed");
    Check(ASC_addPresentationContext(params, static_cast<T_ASC_PresentationContextID>(id), sop_class.c_str(),
                                     list, count),
          "presentation context");
    id += 2;
  }
  static void Check(const OFCondition& status, const std::string& what) {
    if (status.bad()) Fail(ErrorCode::kUnavailable, "DICOM " + what + ": " + status.text());
  }

  T_ASC_Network* network_ = nullptr;
  T_ASC_Association* association_ = nullptr;
  bool established_ = false;
};

std::string StatusText(Uint16 status) {
  char hex[8];
  std::snprintf(hex, sizeof(hex), "0x%04X", status);
  return std::string(hex) + " (" + DU_cstoreStatusString(status) + ")";
}

// Sends one file; returns "" on success, else why it failed.
std::string StoreOne(T_ASC_Association* association, const fs::path& path, const std::string& name,
                     const FileInfo& info, int timeout_s) {
  T_ASC_PresentationContextID id = ASC_findAcceptedPresentationContextID(association, info.sop_class.c_str(),
                                                                         info.transfer_syntax.c_str());
  if (id == 0) return "the peer accepted no presentation context for " + UidName(info.sop_class);
  T_ASC_PresentationContext context;
  ASC_findAcceptedPresentationContext(association->params, id, &context);
  DcmFileFormat file;
  if (file.loadFile(path.c_str()).bad()) return "cannot read " + name;
  DcmDataset* dataset = file.getDataset();
  const E_TransferSyntax accepted = DcmXfer(context.acceptedTransferSyntax).getXfer();
  if (accepted != dataset->getOriginalXfer()) {
    if (dataset->chooseRepresentation(accepted, nullptr).bad() || !dataset->canWriteXfer(accepted)) {
      return "the peer refused " + UidName(info.transfer_syntax) + " for " + UidName(info.sop_class) +
             " and the file cannot be converted to " + UidName(context.acceptedTransferSyntax);
    }
  }
  T_DIMSE_C_StoreRQ request{};
  request.MessageID = association->nextMsgID++;
  OFStandard::strlcpy(request.AffectedSOPClassUID, info.sop_class.c_str(),
                      sizeof(request.AffectedSOPClassUID));
  OFStandard::strlcpy(request.AffectedSOPInstanceUID, info.sop_instance.c_str(),
                      sizeof(request.AffectedSOPInstanceUID));
  request.DataSetType = DIMSE_DATASET_PRESENT;
  request.Priority = DIMSE_PRIORITY_MEDIUM;
  T_DIMSE_C_StoreRSP response{};
  DcmDataset* detail = nullptr;
  const OFCondition status = DIMSE_storeUser(association, id, &request, nullptr, dataset, nullptr, nullptr,
                                             DIMSE_NONBLOCKING, timeout_s, &response, &detail);
  delete detail;
  if (status.bad()) {
    Fail(ErrorCode::kUnavailable, "C-STORE of " + name + " failed: " + status.text());
  }
  const Uint16 code = response.DimseStatus;
  if (code == STATUS_Success || (code & 0xf000) == 0xb000) return "";
  return "C-STORE of " + name + " refused with status " + StatusText(code);
}

}  // namespace

StoreResult StoreFiles(const Peer& peer, const std::vector<fs::path>& files, const StoreSettings& settings,
                       const std::function<void(std::size_t)>& on_stored,
                       const std::vector<std::string>& names) {
  QuietDcmtkLogs();
  std::vector<FileInfo> infos;
  for (const auto& file : files) infos.push_back(Inspect(file));
  StoreResult result;
  result.stored.assign(files.size(), false);
  if (files.empty()) return result;
  Association association;
  association.Open(peer, settings, infos);
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string name = i < names.size() ? names[i] : files[i].filename().string();
    const std::string error = StoreOne(association.get(), files[i], name, infos[i], settings.timeout_s);
    if (error.empty()) {
      result.stored[i] = true;
      if (on_stored) on_stored(i);
    } else if (result.first_error.empty()) {
      result.first_error = error;
    }
  }
  return result;
}

}  // namespace endorecon::dicom
