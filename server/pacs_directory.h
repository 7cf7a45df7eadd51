// The PACS the server knows by name (--pacs NAME=AET@HOST:PORT) and its own DICOM identity
// (--ae-title, --dicom-listen, --uid-root). Workers never talk to a PACS; the server does.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/dicom/peer.h"

namespace endorecon::server {

struct DicomSettings {
  std::string ae_title = "ENDORECON";  // this server's AE title, calling and (SCP) called
  std::string listen;                  // "HOST:PORT" of the storage SCP for C-MOVE; "": none
  std::string uid_root;                // root of new UIDs in results; "": 2.25 UUID UIDs
  int send_attempts = 5;               // C-STORE attempts per destination before SEND_FAILED
  int send_backoff_ms = 2000;          // wait before the second attempt, doubled each time (max 60 s)
  int retrieve_attempts = 8;           // retrieval attempts while the PACS does not answer
  int retrieve_backoff_ms = 2000;      // as send_backoff_ms (8 attempts span about 3 minutes)
  int timeout_s = 30;                  // connect, association and each DIMSE response
};

// The wait before attempt `attempt` + 1 when the first wait is `first_ms`: doubled for each further
// attempt, at most a minute.
std::int64_t RetryWaitMs(int first_ms, int attempt);

// Audits what the server did with a PACS on its own: method ("PacsRetrieve", "PacsSend"), job,
// outcome ("OK" or why not, as a status name) and the PACS's name.
using PacsAudit = std::function<void(const std::string& method, const std::string& job_id,
                                     const std::string& outcome, const std::string& pacs)>;

class PacsDirectory {
 public:
  // `flags`: "NAME=AET@HOST:PORT" each. Throws InvalidArgument naming the flag for a bad form or a
  // name given twice.
  explicit PacsDirectory(const std::vector<std::string>& flags);
  // Throws kNotFound naming the PACS and the ones that exist.
  const dicom::Peer& Find(const std::string& name) const;
  bool empty() const { return peers_.empty(); }
  std::vector<std::string> Names() const;

 private:
  std::map<std::string, dicom::Peer> peers_;
};

}  // namespace endorecon::server
