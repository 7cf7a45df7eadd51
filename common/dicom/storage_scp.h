// The server's own storage SCP: the PACS connects back to it to deliver a C-MOVE. Each received
// instance is written to <folder>/<Study UID>/<Series UID>/<SOP Instance UID>.dcm (a temporary name,
// then renamed, so a reader never sees half a file). Accepts the recording SOP classes and
// transfer syntaxes of storage_classes.h and C-ECHO.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace endorecon::dicom {

struct StorageScpSettings {
  std::string ae_title = "ENDORECON";
  int port = 11112;
  std::filesystem::path folder;
  std::vector<std::string> calling_ae_titles;  // who may store here (the configured PACS); empty: anyone
};

class StorageScp {
 public:
  // Called for each instance stored: its study, its file and its size in bytes.
  using OnStored = std::function<void(const std::string& study_uid, const std::filesystem::path& file,
                                      std::int64_t bytes)>;

  // Whether an instance of this study is awaited (a C-MOVE in progress): others are refused, so a
  // PACS (or anyone calling as one) cannot leave unasked-for patient data on the server.
  using Awaits = std::function<bool(const std::string& study_uid)>;

  // Opens the port and starts serving associations in a thread. DCMTK 3.6.7 binds the port on
  // every interface and cannot tell which host calls: associations are admitted by calling AE title
  // (the configured PACS) and called AE title (this SCP's), instances by `awaits`.
  // Throws Error(kUnavailable) when the port cannot be opened.
  StorageScp(const StorageScpSettings& settings, OnStored on_stored, Awaits awaits);
  // Stops after the association in progress (within a second when idle) and joins the thread.
  ~StorageScp();
  StorageScp(const StorageScp&) = delete;
  StorageScp& operator=(const StorageScp&) = delete;

  const StorageScpSettings& settings() const { return settings_; }

 private:
  class Scp;
  StorageScpSettings settings_;
  std::unique_ptr<Scp> scp_;
  std::thread thread_;
};

}  // namespace endorecon::dicom
