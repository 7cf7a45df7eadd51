#include "server/upload_receiver.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <set>
#include <string>
#include <thread>

#include "common/error.h"
#include "common/sha256.h"
#include "tests/fuzz/message_stream.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

using Clock = std::chrono::steady_clock;
using Stream = fuzz::ServerStreamOf<v1::UploadRequest>;

v1::UploadRequest ManifestOf(const std::string& path, const std::string& bytes) {
  v1::UploadRequest request;
  auto* entry = request.mutable_manifest()->add_files();
  entry->set_path(path);
  entry->set_size(static_cast<std::int64_t>(bytes.size()));
  entry->set_sha256(Sha256Hex(bytes));
  return request;
}

v1::UploadRequest ChunkOf(const std::string& path, const std::string& bytes) {
  v1::UploadRequest request;
  request.mutable_chunk()->set_path(path);
  request.mutable_chunk()->set_data(bytes);
  return request;
}

// --max-upload-bytes limits what clients send. A worker's results (of a job already accepted) were
// refused by it too, and the job failed after training, once per attempt (found 2026-12-05).
TEST(UploadReceiverTest, TheUploadLimitIsOnClientsNotOnAWorkersResults) {
  testing::TempDir dir("uploads");
  BlobStore blobs(dir.path());
  UploadReceiver receiver(blobs, /*max_upload_bytes=*/10, 0, /*max_streams=*/1, {});
  const auto manifest = ManifestOf("results.bin", std::string(64, 'r')).manifest();
  try {
    receiver.Query(manifest, Uploader::kClient);
    ADD_FAILURE() << "a client's upload over the limit was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
  }
  EXPECT_EQ(receiver.Query(manifest, Uploader::kWorker).total_bytes(), 64);
  Stream stream(
      {ManifestOf("results.bin", std::string(64, 'r')), ChunkOf("results.bin", std::string(64, 'r'))});
  EXPECT_TRUE(receiver.Receive(stream, Uploader::kWorker).complete());
}

// Content another tenant holds counts as not stored for this one (BlobHolders): its bytes are sent
// again into the tenant's own partial, resumed across streams like any upload, and only a whole
// partial whose digest checks out is told proven; wrong bytes are discarded and prove nothing.
TEST(UploadReceiverTest, ContentAnotherTenantHoldsIsSentAgainAsProof) {
  testing::TempDir dir("uploads");
  BlobStore blobs(dir.path());
  UploadReceiver receiver(blobs, 1 << 20, 0, /*max_streams=*/1, {});
  const std::string bytes = "another tenant's patient, byte for byte";
  const auto sha = blobs.Put(bytes);
  std::set<std::string> proven;
  UploadOwner owner;
  owner.tenant = "a";
  owner.unproven = [&](const v1::Manifest&) {
    return proven.count(sha) ? std::set<std::string>{} : std::set<std::string>{sha};
  };
  owner.proven = [&](const std::string& digest) { proven.insert(digest); };
  const auto manifest = ManifestOf("clip/frame.png", bytes);

  auto status = receiver.Query(manifest.manifest(), Uploader::kClient, owner);
  EXPECT_EQ(status.files(0).committed(), 0);
  EXPECT_FALSE(status.complete());
  EXPECT_TRUE(receiver.Query(manifest.manifest(), Uploader::kClient).complete()) << "the server's own view";

  Stream forged({manifest, ChunkOf("clip/frame.png", std::string(bytes.size(), 'x'))});
  try {
    receiver.Receive(forged, Uploader::kClient, owner);
    ADD_FAILURE() << "bytes that are not the content were taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
  }
  EXPECT_TRUE(proven.empty());
  EXPECT_EQ(testing::ReadBytes(blobs.PathOf(sha)), bytes);

  const auto half = bytes.size() / 2;
  Stream first({manifest, ChunkOf("clip/frame.png", bytes.substr(0, half))});
  status = receiver.Receive(first, Uploader::kClient, owner);
  EXPECT_EQ(status.files(0).committed(), static_cast<std::int64_t>(half));
  EXPECT_FALSE(status.complete());
  EXPECT_TRUE(proven.empty());
  auto rest = ChunkOf("clip/frame.png", bytes.substr(half));
  rest.mutable_chunk()->set_offset(static_cast<std::int64_t>(half));
  Stream second({manifest, rest});
  EXPECT_TRUE(receiver.Receive(second, Uploader::kClient, owner).complete());
  EXPECT_EQ(proven, std::set<std::string>{sha});
  EXPECT_EQ(blobs.PartialBytes(manifest.manifest().files(0), "a"), 0);
  EXPECT_EQ(testing::ReadBytes(blobs.PathOf(sha)), bytes);
}

// A manifest without digests asks only whether its sizes may come; an upload must name them.
TEST(UploadReceiverTest, ASizesOnlyQueryIsCheckedAgainstTheLimitAndAnUploadNeedsDigests) {
  testing::TempDir dir("uploads");
  BlobStore blobs(dir.path());
  UploadReceiver receiver(blobs, /*max_upload_bytes=*/100, 0, /*max_streams=*/1, {});
  auto request = ManifestOf("a.bin", std::string(64, 'a'));
  request.mutable_manifest()->mutable_files(0)->clear_sha256();
  const auto status = receiver.Query(request.manifest(), Uploader::kClient);
  EXPECT_EQ(status.total_bytes(), 64);
  EXPECT_FALSE(status.complete());
  request.mutable_manifest()->mutable_files(0)->set_size(101);
  EXPECT_THROW(receiver.Query(request.manifest(), Uploader::kClient), Error);
  request.mutable_manifest()->mutable_files(0)->set_size(64);
  Stream stream({request, ChunkOf("a.bin", std::string(64, 'a'))});
  try {
    receiver.Receive(stream, Uploader::kClient);
    ADD_FAILURE() << "an upload without digests was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
  }
}

// An upload waiting for a slot held no thread of its own until the slot came free: a client that
// gave up (its deadline, or cancelled) still kept the server's thread, which then took the slot.
TEST(UploadReceiverTest, AnUploadCancelledWhileItWaitsForASlotStopsWaiting) {
  testing::TempDir dir("uploads");
  BlobStore blobs(dir.path());
  UploadReceiver receiver(blobs, 1 << 20, 0, /*max_streams=*/1, {});

  // The only slot is taken by an upload whose sender stops after its manifest.
  std::atomic<bool> holding{false}, release{false};
  std::thread holder([&] {
    Stream stream({ManifestOf("held.bin", "bytes that come late")});
    int reads = 0;
    receiver.Receive(stream, Uploader::kClient, {}, {}, [&](const std::function<bool()>& read) {
      if (reads++ > 0) {  // past the manifest: the slot is held
        holding = true;
        while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      return read();
    });
  });
  while (!holding) std::this_thread::sleep_for(std::chrono::milliseconds(10));

  const auto start = Clock::now();
  Stream waiting({ManifestOf("a.bin", "abc"), ChunkOf("a.bin", "abc")});
  try {
    receiver.Receive(waiting, Uploader::kClient, {}, {}, {},
                     [&] { return Clock::now() - start > std::chrono::milliseconds(300); });
    ADD_FAILURE() << "the upload waited for the slot to the end";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
    EXPECT_NE(std::string(e.what()).find("--max-uploads"), std::string::npos) << e.what();
  }
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(5));
  EXPECT_FALSE(blobs.Has(Sha256Hex("abc")));

  release = true;
  holder.join();
  // The slot is free again: the next upload goes through.
  Stream next({ManifestOf("a.bin", "abc"), ChunkOf("a.bin", "abc")});
  EXPECT_TRUE(receiver.Receive(next, Uploader::kClient).complete());
  EXPECT_TRUE(blobs.Has(Sha256Hex("abc")));
}

}  // namespace
}  // namespace endorecon::server
