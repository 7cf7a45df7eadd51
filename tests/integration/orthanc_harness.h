// A real Orthanc (Debian's `orthanc`) for the PACS tests: started on loopback with its own
// configuration and storage folder, reached over DICOM and its REST API (through curl).
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {

// An AE that Orthanc knows (its DicomModalities): where it sends C-MOVE deliveries, and what it allows.
struct OrthancModality {
  std::string ae_title;
  int port = 0;  // of the AE's storage SCP (for C-MOVE)
  bool allow_get = true;
};

class Orthanc {
 public:
  // Writes the configuration (AE title ORTHANC, the called AE title checked, no plugins) into
  // `folder`; call Start() to run it.
  Orthanc(const std::filesystem::path& folder, std::vector<OrthancModality> modalities);
  // Starts Orthanc and waits up to 20 s for its REST API. Returns "" when it runs, else why not.
  std::string Start();
  void Stop();

  int dicom_port() const { return dicom_port_; }
  // "ORTHANC@127.0.0.1:<port>".
  std::string Address() const;
  // REST calls; a failure (no JSON back) returns a null value.
  nlohmann::json Get(const std::string& uri) const;
  std::string GetText(const std::string& uri) const;
  nlohmann::json Post(const std::string& uri, const std::string& body) const;
  // Stores a DICOM file through the REST API; returns Orthanc's answer.
  nlohmann::json Store(const std::filesystem::path& file) const;

 private:
  std::filesystem::path folder_;
  int http_port_ = 0, dicom_port_ = 0;
  std::unique_ptr<Process> process_;
};

}  // namespace endorecon::testing
