// Manifests as they arrive from the network: validated by the server (ValidateManifest, TotalBytes)
// and, for a job's results, turned into downloads by the CLI (PendingDownloads) in a results folder
// that already holds a file and a partial one.
#include "common/file_download.h"
#include "common/manifest.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

const std::filesystem::path& ResultsDir() {
  static const std::filesystem::path dir = [] {
    const auto path = endorecon::fuzz::ScratchDir() / "results";
    std::filesystem::create_directories(path / "eval");
    endorecon::fuzz::WriteInput("results/summary.json", "{}");
    endorecon::fuzz::WriteInput("results/eval/frame.png.part", "partial");
    return path;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  v1::Manifest manifest;
  if (!manifest.ParseFromArray(data, static_cast<int>(size))) return 0;
  if (fuzz::Accepts([&] { ValidateManifest(manifest); }, {ErrorCode::kInvalidArgument})) {
    if (TotalBytes(manifest) < 0) fuzz::Broken("a valid manifest with a negative total");
  }
  std::vector<v1::FileRange> pending;
  if (!fuzz::Accepts([&] { pending = PendingDownloads(ResultsDir(), manifest); },
                     {ErrorCode::kInvalidArgument}))
    return 0;
  for (const auto& range : pending) {
    if (range.offset() < 0) fuzz::Broken("a download from a negative offset");
  }
  return 0;
}
