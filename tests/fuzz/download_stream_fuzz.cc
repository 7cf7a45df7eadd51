// The CLI's and the worker's side of a download (ReceiveFiles: results from Fetch, clips and
// checkpoints from GetBlobs) fed a stream of FileChunks (tests/fuzz/message_stream.h), as a server
// that is broken or not ours could send. Whatever arrives, a file lands under its name only with the
// digest its header promised, and nothing is written outside the folder.
#include <set>
#include <utility>

#include "common/file_download.h"
#include "common/sha256.h"
#include "tests/fuzz/fuzz_input.h"
#include "tests/fuzz/message_stream.h"

namespace {

namespace fs = std::filesystem;
using namespace endorecon;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path root = fuzz::ScratchDir() / "download";
  fs::remove_all(root);
  const fs::path dir = root / "into";
  fs::create_directories(dir);
  const auto messages = fuzz::MessagesOf<v1::FileChunk>(data, size);
  fuzz::ClientStreamOf<v1::FileChunk> stream(messages);
  fuzz::Accepts([&] { ReceiveFiles(stream, dir); },
                {ErrorCode::kInvalidArgument, ErrorCode::kDataLoss, ErrorCode::kUnavailable,
                 ErrorCode::kInternal});                   // a local write that failed
  std::set<std::pair<std::string, std::string>> promised;  // (path, sha256) of every file header
  for (const auto& chunk : messages) {
    if (chunk.has_file()) promised.emplace(chunk.file().path(), chunk.file().sha256());
  }
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    const auto relative = fs::relative(entry.path(), dir);
    if (relative.empty() || *relative.begin() == "..")
      fuzz::Broken("a file outside the folder: " + entry.path().string());
    if (!entry.is_regular_file() || entry.path().extension() == ".part") continue;
    if (!promised.count({relative.generic_string(), Sha256File(entry.path())}))
      fuzz::Broken("a file landed without the digest its header promised: " + relative.string());
  }
  return 0;
}
