#include "tests/integration/orthanc_harness.h"

#include <csignal>
#include <fstream>
#include <thread>

namespace endorecon::testing {
namespace fs = std::filesystem;

Orthanc::Orthanc(const fs::path& folder, std::vector<OrthancModality> modalities) : folder_(folder) {
  http_port_ = FreePort();
  dicom_port_ = FreePort();
  nlohmann::json known = nlohmann::json::object();
  for (const auto& modality : modalities) {
    known[modality.ae_title] = {{"AET", modality.ae_title},
                                {"Host", "127.0.0.1"},
                                {"Port", modality.port},
                                {"AllowEcho", true},
                                {"AllowFind", true},
                                {"AllowMove", true},
                                {"AllowGet", modality.allow_get},
                                {"AllowStore", true}};
  }
  const nlohmann::json config = {{"Name", "endorecon-test"},
                                 {"StorageDirectory", (folder / "db").string()},
                                 {"IndexDirectory", (folder / "db").string()},
                                 {"Plugins", nlohmann::json::array()},
                                 {"HttpPort", http_port_},
                                 {"RemoteAccessAllowed", false},
                                 {"AuthenticationEnabled", false},
                                 {"DicomServerEnabled", true},
                                 {"DicomAet", "ORTHANC"},
                                 {"DicomPort", dicom_port_},
                                 {"DicomCheckCalledAet", true},
                                 {"DicomAlwaysAllowStore", true},
                                 {"DicomAlwaysAllowGet", false},
                                 {"DicomAlwaysAllowMove", false},
                                 {"DicomCheckModalityHost", false},
                                 {"DicomModalities", known},
                                 {"DicomScpTimeout", 10},
                                 {"SaveJobs", false}};
  fs::create_directories(folder);
  std::ofstream(folder / "orthanc.json") << config.dump(1);
}

std::string Orthanc::Start() {
  if (!fs::exists("/usr/sbin/Orthanc")) return "Orthanc is not installed (Debian package orthanc)";
  process_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/sbin/Orthanc", (folder_ / "orthanc.json").string()},
      folder_ / "orthanc.log");
  const bool up = WaitUntil([&] { return Get("/system").is_object(); }, std::chrono::seconds(20));
  if (up) return "";
  std::ifstream log(folder_ / "orthanc.log");
  std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  Stop();
  return "Orthanc did not start within 20 s: " + text.substr(text.size() > 800 ? text.size() - 800 : 0);
}

void Orthanc::Stop() {
  if (!process_) return;
  process_->Signal(SIGTERM);
  process_->Wait();
  process_.reset();
}

std::string Orthanc::Address() const { return "ORTHANC@127.0.0.1:" + std::to_string(dicom_port_); }

nlohmann::json Orthanc::Get(const std::string& uri) const {
  return nlohmann::json::parse(GetText(uri), nullptr, false);
}

std::string Orthanc::GetText(const std::string& uri) const {
  return Capture("curl -s --max-time 10 http://127.0.0.1:" + std::to_string(http_port_) + uri);
}

nlohmann::json Orthanc::Post(const std::string& uri, const std::string& body) const {
  const fs::path request = folder_ / "request.json";
  std::ofstream(request) << body;
  const auto text = Capture("curl -s --max-time 30 -X POST --data-binary @" + request.string() +
                            " http://127.0.0.1:" + std::to_string(http_port_) + uri);
  return nlohmann::json::parse(text, nullptr, false);
}

nlohmann::json Orthanc::Store(const fs::path& file) const {
  const auto text = Capture("curl -s --max-time 30 -X POST --data-binary @" + file.string() +
                            " http://127.0.0.1:" + std::to_string(http_port_) + "/instances");
  return nlohmann::json::parse(text, nullptr, false);
}

}  // namespace endorecon::testing
