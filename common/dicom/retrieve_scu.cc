#include "common/dicom/retrieve_scu.h"

#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmnet/diutil.h>
#include <dcmtk/dcmnet/scu.h>

#include <set>
#include <string>
#include <string_view>

#include "common/dicom/dataset_access.h"
#include "common/dicom/dcmtk_logging.h"
#include "common/dicom/storage_classes.h"
#include "common/error.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;
namespace {

// DcmSCU counting what C-GET stores (DcmSCU writes each instance into its storage folder, under
// the name it asks createStorageFilename for).
class RetrievingScu : public DcmSCU {
 public:
  RetrieveProgress progress;
  int instances = 0;
  std::int64_t bytes = 0;

 protected:
  OFString createStorageFilename(DcmDataset* dataset) override {
    last_file_ = DcmSCU::createStorageFilename(dataset);
    return last_file_;
  }

  OFCondition handleSTORERequest(const T_ASC_PresentationContextID id, DcmDataset* incoming, OFBool& go_on,
                                 Uint16& status) override {
    if (incoming != nullptr && IsEndoreconResult(*incoming)) {  // taken, not kept (storage_classes.h)
      status = STATUS_Success;
      return EC_Normal;
    }
    last_file_.clear();
    const OFCondition result = DcmSCU::handleSTORERequest(id, incoming, go_on, status);
    std::error_code error;
    const auto size = last_file_.empty() ? 0 : fs::file_size(last_file_.c_str(), error);
    if (result.good() && !error) {
      ++instances;
      bytes += static_cast<std::int64_t>(size);
      if (progress) progress(instances, bytes);
    }
    return result;
  }

 private:
  OFString last_file_;
};

void Configure(DcmSCU& scu, const RetrieveRequest& request) {
  scu.setAETitle(request.calling_ae_title.c_str());
  scu.setPeerAETitle(request.peer.ae_title.c_str());
  scu.setPeerHostName(request.peer.host.c_str());
  scu.setPeerPort(static_cast<Uint16>(request.peer.port));
  scu.setACSETimeout(static_cast<Uint32>(request.timeout_s));
  scu.setDIMSETimeout(static_cast<Uint32>(request.timeout_s));
  scu.setDIMSEBlockingMode(DIMSE_NONBLOCKING);
  scu.setConnectionTimeout(request.timeout_s);
}

void Connect(DcmSCU& scu, const RetrieveRequest& request) {
  const std::string where = "association with " + PeerText(request.peer);
  OFCondition status = scu.initNetwork();
  if (status.good()) status = scu.negotiateAssociation();
  if (status.bad()) {
    // DcmSCU keeps the peer's reason to itself (its log): what a rejection usually means is said.
    // A PACS that does not answer may be back soon (UNAVAILABLE: the server retries); one that
    // refuses this server stays so until someone changes a configuration (FAILED_PRECONDITION, as
    // every failure once the association stands: Orthanc aborts a C-GET it does not allow).
    const bool rejected = std::string_view(status.text()).find("Rejected") != std::string_view::npos;
    Fail(rejected ? ErrorCode::kFailedPrecondition : ErrorCode::kUnavailable,
         where + " failed: " + status.text() +
             (rejected ? " (the PACS refused this server: is " + request.peer.ae_title +
                             " its AE title, and does it accept calls from AE title " +
                             request.calling_ae_title + " at this host?)"
                       : ""));
  }
}

DcmDataset Query(const RetrieveRequest& request) {
  DcmDataset query;
  Put(query, DCM_QueryRetrieveLevel, request.series_uid.empty() ? "STUDY" : "SERIES");
  Put(query, DCM_StudyInstanceUID, request.study_uid);
  if (!request.series_uid.empty()) Put(query, DCM_SeriesInstanceUID, request.series_uid);
  return query;
}

// Messages name the level, not the UIDs: they reach logs, and UIDs lead to a patient.
std::string What(const RetrieveRequest& request) {
  return request.series_uid.empty() ? "the study" : "the series";
}

// A DIMSE status as DICOM writes it: 0xC000.
std::string StatusText(Uint16 status) {
  char hex[8];
  std::snprintf(hex, sizeof(hex), "0x%04X", status);
  return hex;
}

// Connects and returns the presentation context of `model` (a Study Root query/retrieve model),
// releasing the association and failing, naming `verb`, when the peer does not offer it.
T_ASC_PresentationContextID Associate(DcmSCU& scu, const RetrieveRequest& request, const char* model,
                                      const std::string& verb) {
  Connect(scu, request);
  const T_ASC_PresentationContextID id = scu.findPresentationContextID(model, "");
  if (id == 0) {
    scu.releaseAssociation();
    Fail(ErrorCode::kFailedPrecondition,
         PeerText(request.peer) + " does not offer " + verb + " (Study Root)");
  }
  return id;
}

// What a PACS needs to send a C-MOVE to this server.
constexpr const char* kMoveDestinationAdvice =
    "it must list this server's AE title at the host and port of its --dicom-listen";

// Checks the final response; returns the completed sub-operations.
int Finish(const OFList<RetrieveResponse*>& responses, const RetrieveRequest& request,
           const std::string& verb) {
  if (responses.empty())
    Fail(ErrorCode::kFailedPrecondition, verb + " of " + What(request) + ": no response");
  const RetrieveResponse* last = responses.back();
  const std::string status = StatusText(last->m_status);
  if (last->m_status != STATUS_Success && (last->m_status & 0xf000) != 0xb000) {
    // The PACS's own words, when it sent any; and what a failure usually means here: a PACS fails a
    // whole retrieval when the study is not there, or when one of its objects (a CT, a report) is of
    // a class endorecon does not take (only the recording's series can come then).
    const std::string comment = last->m_statusDetail == nullptr
                                    ? ""
                                    : FindString(*last->m_statusDetail, DCM_ErrorComment).value_or("");
    Fail(ErrorCode::kFailedPrecondition,
         verb + " of " + What(request) + " refused by " + PeerText(request.peer) + " with status " + status +
             (comment.empty() ? "" : " (\"" + comment + "\")") +
             (last->m_status == 0xa801
                  ? std::string(": the PACS does not know the move destination: ") + kMoveDestinationAdvice
              : (last->m_status & 0xf000) == 0xc000 || last->m_status == 0xa701 || last->m_status == 0xa702
                  ? std::string(": the PACS may not hold it") +
                        (request.series_uid.empty()
                             ? ", or the study holds objects other than a recording (a CT, a report), "
                               "which endorecon does not take: name the recording's series with --series UID"
                             : "") +
                        (verb.rfind("C-MOVE", 0) == 0
                             ? std::string("; or it cannot reach the move destination: ") +
                                   kMoveDestinationAdvice
                             : "")
                  : ""));
  }
  if (last->m_numberOfFailedSubops > 0) {
    Fail(ErrorCode::kDataLoss, verb + " of " + What(request) + ": " +
                                   std::to_string(last->m_numberOfFailedSubops) +
                                   " instance(s) failed (status " + status + ")");
  }
  return last->m_numberOfCompletedSubops;
}

void FreeAll(OFList<RetrieveResponse*>& responses) {
  for (auto* response : responses) delete response;
  responses.clear();
}

// Connects, finds the presentation context of `model`, sends the request through `send` and
// checks the final response; returns the completed sub-operations. The association is released
// on every path.
using SendRequest =
    std::function<OFCondition(T_ASC_PresentationContextID, DcmDataset*, OFList<RetrieveResponse*>*)>;
int Retrieve(DcmSCU& scu, const RetrieveRequest& request, const char* model, const std::string& verb,
             const SendRequest& send) {
  const T_ASC_PresentationContextID id = Associate(scu, request, model, verb);
  DcmDataset query = Query(request);
  OFList<RetrieveResponse*> responses;
  const OFCondition status = send(id, &query, &responses);
  scu.releaseAssociation();
  try {
    // A PACS that will not serve this AE title (Orthanc's per-modality rights) aborts the association
    // after accepting it rather than answering with a status: that was said with no hint (found
    // 2026-12-07).
    if (status.bad()) {
      const std::string text = status.text();
      Fail(ErrorCode::kFailedPrecondition,
           verb + " of " + What(request) + " failed: " + text +
               (text.find("abort") != std::string::npos || text.find("Abort") != std::string::npos
                    ? ": the PACS accepted the association, then aborted it: does it allow " +
                          request.calling_ae_title + " to " + verb.substr(0, verb.find(' ')) +
                          " (its settings for this AE title)?" +
                          (request.series_uid.empty()
                               ? " Or it refuses the study's other objects (a CT, a "
                                 "report): name the recording's series with --series UID"
                               : "")
                    : ""));
    }
    const int completed = Finish(responses, request, verb);
    FreeAll(responses);
    return completed;
  } catch (...) {
    FreeAll(responses);
    throw;
  }
}

OFList<OFString> Uncompressed() {
  OFList<OFString> plain;
  plain.push_back(UID_LittleEndianExplicitTransferSyntax);
  plain.push_back(UID_LittleEndianImplicitTransferSyntax);
  return plain;
}

}  // namespace

int GetStudy(const RetrieveRequest& request, const fs::path& out_dir, const RetrieveProgress& progress) {
  QuietDcmtkLogs();
  fs::create_directories(out_dir);
  RetrievingScu scu;
  Configure(scu, request);
  scu.progress = progress;
  scu.setStorageDir(out_dir.c_str());
  scu.setStorageMode(DCMSCU_STORAGE_DISK);
  scu.addPresentationContext(UID_GETStudyRootQueryRetrieveInformationModel, Uncompressed());
  // One context per transfer syntax: the PACS sends each instance as it holds it, and a video
  // cannot be transcoded.
  for (const auto& storage : RecordingStorageClasses()) {
    for (const auto& ts : storage.transfer_syntaxes) {
      OFList<OFString> one;
      one.push_back(ts.c_str());
      scu.addPresentationContext(storage.sop_class.c_str(), one, ASC_SC_ROLE_SCP);
    }
  }
  Retrieve(scu, request, UID_GETStudyRootQueryRetrieveInformationModel, "C-GET",
           [&](T_ASC_PresentationContextID id, DcmDataset* query, OFList<RetrieveResponse*>* responses) {
             return scu.sendCGETRequest(id, query, responses);
           });
  if (scu.instances == 0) {
    Fail(ErrorCode::kNotFound, PeerText(request.peer) + " holds no recording in " + What(request) +
                                   " (endorecon's own results there are not one)");
  }
  return scu.instances;
}

StudyContents FindStudyContents(const RetrieveRequest& request) {
  QuietDcmtkLogs();
  DcmSCU scu;
  Configure(scu, request);
  scu.addPresentationContext(UID_FINDStudyRootQueryRetrieveInformationModel, Uncompressed());
  const T_ASC_PresentationContextID id =
      Associate(scu, request, UID_FINDStudyRootQueryRetrieveInformationModel, "C-FIND");
  DcmDataset query;
  Put(query, DCM_QueryRetrieveLevel, "IMAGE");
  Put(query, DCM_StudyInstanceUID, request.study_uid);
  Put(query, DCM_SeriesInstanceUID, "");
  Put(query, DCM_SOPClassUID, "");
  Put(query, DCM_SOPInstanceUID, "");
  OFList<QRResponse*> responses;
  const OFCondition status = scu.sendFINDRequest(id, &query, &responses);
  scu.releaseAssociation();
  std::set<std::string> accepted;
  for (const auto& storage : RecordingStorageClasses()) accepted.insert(storage.sop_class);
  std::vector<std::string> order;
  std::map<std::string, bool> all_accepted;  // series -> every instance of a class endorecon takes
  StudyContents contents;
  std::string refusal;
  for (QRResponse* response : responses) {
    if (response->m_dataset != nullptr) {
      const std::string series = FindString(*response->m_dataset, DCM_SeriesInstanceUID).value_or("");
      const std::string sop_class = FindString(*response->m_dataset, DCM_SOPClassUID).value_or("");
      if (!all_accepted.contains(series)) {
        order.push_back(series);
        all_accepted[series] = true;
      }
      // A PACS that returns no SOP Class UID at the image level (DCMTK's dcmqrscp) says nothing of the
      // class: taken as a recording's, the worker then skipping what is none (every retrieval from such
      // a PACS failed, "only objects of classes endorecon does not take (an unnamed class x 1)"; found
      // 2026-12-07).
      if (!sop_class.empty() && !accepted.contains(sop_class)) {
        all_accepted[series] = false;
        ++contents.other_classes[dcmFindNameOfUID(sop_class.c_str(), sop_class.c_str())];
      }
    }
    if (response == responses.back() && response->m_status != STATUS_Success) {
      refusal = "status " + StatusText(response->m_status);
    }
    delete response;
  }
  const std::string where = "C-FIND of the study's instances at " + PeerText(request.peer);
  if (status.bad()) Fail(ErrorCode::kFailedPrecondition, where + " failed: " + status.text());
  if (!refusal.empty()) Fail(ErrorCode::kFailedPrecondition, where + " refused: " + refusal);
  for (const std::string& series : order) {
    if (series.empty()) continue;
    if (all_accepted[series]) {
      contents.recording_series.push_back(series);
    } else {
      ++contents.other_series;
    }
  }
  return contents;
}

int MoveStudy(const RetrieveRequest& request, const std::string& destination_ae) {
  QuietDcmtkLogs();
  DcmSCU scu;
  Configure(scu, request);
  scu.addPresentationContext(UID_MOVEStudyRootQueryRetrieveInformationModel, Uncompressed());
  const int moved =
      Retrieve(scu, request, UID_MOVEStudyRootQueryRetrieveInformationModel, "C-MOVE to " + destination_ae,
               [&](T_ASC_PresentationContextID id, DcmDataset* query, OFList<RetrieveResponse*>* responses) {
                 return scu.sendMOVERequest(id, destination_ae.c_str(), query, responses);
               });
  if (moved == 0)
    Fail(ErrorCode::kNotFound, PeerText(request.peer) + " holds no recording in " + What(request) +
                                   " (endorecon's own results there are not one)");
  return moved;
}

}  // namespace endorecon::dicom
