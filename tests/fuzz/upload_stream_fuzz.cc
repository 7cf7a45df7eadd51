// The upload stream handler (server::UploadReceiver::Receive, behind JobService.Upload and
// WorkerService.PutBlobs) fed a stream of UploadRequests (tests/fuzz/message_stream.h) over a real
// blob store in a fresh folder. Whatever the stream holds, every blob it leaves is exactly the
// content its name says, every partial file is no longer than its content, and nothing is written
// outside blobs/ and partial/.
#include <grpcpp/support/sync_stream.h>

#include "common/sha256.h"
#include "server/upload_receiver.h"
#include "tests/fuzz/fuzz_input.h"
#include "tests/fuzz/message_stream.h"

namespace {

namespace fs = std::filesystem;
using namespace endorecon;

void CheckStore(const fs::path& root) {
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    const auto relative = fs::relative(entry.path(), root);
    const auto top = *relative.begin();
    if (top != "blobs" && top != "partial")
      fuzz::Broken("a file outside blobs/ and partial/: " + relative.string());
    if (!entry.is_regular_file()) continue;
    if (top == "blobs" && Sha256File(entry.path()) != entry.path().filename().string())
      fuzz::Broken("blob " + relative.string() + " does not hold the content its name says");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path root = fuzz::ScratchDir() / "store";
  fs::remove_all(root);
  server::BlobStore blobs(root);
  server::UploadReceiver receiver(blobs, 1 << 20, 0, 1, {});
  fuzz::ServerStreamOf<v1::UploadRequest> stream(fuzz::MessagesOf<v1::UploadRequest>(data, size));
  // Each refusal the handler documents; kFailedPrecondition: a chunk past the committed bytes.
  fuzz::Accepts([&] { receiver.Receive(stream, server::Uploader::kClient); },
                {ErrorCode::kInvalidArgument, ErrorCode::kResourceExhausted, ErrorCode::kDataLoss,
                 ErrorCode::kFailedPrecondition});
  CheckStore(root);
  return 0;
}
