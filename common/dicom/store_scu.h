// C-STORE of DICOM files to a peer (a PACS), one association per call.
//
// Presentation contexts: one per SOP class with the files' own transfer syntax when it is
// compressed, and one with Explicit and Implicit VR Little Endian. A file goes on the context of
// its own transfer syntax when the peer accepted it, else on an uncompressed one (DCMTK decodes it
// first: JPEG and RLE can be, MPEG video cannot, and that file fails with the reason).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/dicom/peer.h"

namespace endorecon::dicom {

struct StoreSettings {
  std::string calling_ae_title = "ENDORECON";
  int timeout_s = 30;  // connect, association and each response
};

struct StoreResult {
  std::vector<bool> stored;  // per file: the peer answered success (or a warning)
  std::string first_error;   // why the first file that failed failed, with the peer's status
};

// Sends `files` and reports each success through `on_stored(index)`. Throws Error(kUnavailable)
// when the peer cannot be reached or the association fails, with the peer's reason when it
// rejected it (e.g. "rejected (permanent) by the called AE: called AE title not recognized").
// Messages call file i `names[i]` when given (a result's path, not its blob's digest), else its
// file name.
StoreResult StoreFiles(const Peer& peer, const std::vector<std::filesystem::path>& files,
                       const StoreSettings& settings, const std::function<void(std::size_t)>& on_stored = {},
                       const std::vector<std::string>& names = {});

}  // namespace endorecon::dicom
