#include "server/blob_store.h"

#include <gtest/gtest.h>

#include <chrono>
#include <map>

#include "common/error.h"
#include "common/sha256.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

v1::FileEntry EntryOf(const std::string& path, const std::string& bytes) {
  v1::FileEntry entry;
  entry.set_path(path);
  entry.set_size(static_cast<std::int64_t>(bytes.size()));
  entry.set_sha256(Sha256Hex(bytes));
  return entry;
}

ErrorCode CodeOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "expected an error";
  return ErrorCode::kInternal;
}

TEST(BlobStoreTest, PutStoresContentUnderItsDigest) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  const std::string sha = store.Put("hello");
  EXPECT_EQ(sha, Sha256Hex("hello"));
  EXPECT_TRUE(store.Has(sha));
  EXPECT_EQ(testing::ReadBytes(store.PathOf(sha)), "hello");
  EXPECT_EQ(CodeOf([&] { store.PathOf(Sha256Hex("other")); }), ErrorCode::kNotFound);
}

// A blob the disk damaged is told by its digest and set aside out of the store, kept for an admin.
TEST(BlobStoreTest, ADamagedBlobIsToldByItsDigestAndSetAside) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  const std::string sha = store.Put("hello, tissue");
  EXPECT_TRUE(store.Intact(sha));
  testing::WriteBytes(store.PathOf(sha), "hello, tiSsue");
  EXPECT_FALSE(store.Intact(sha));
  EXPECT_FALSE(store.Intact(Sha256Hex("never stored")));
  const auto aside = store.SetAsideDamaged(sha, "images/000003.png");
  EXPECT_FALSE(store.Has(sha)) << "the next upload of the content stores it anew";
  EXPECT_EQ(aside.parent_path(), dir.path() / "damaged");
  EXPECT_EQ(testing::ReadBytes(aside), "hello, tiSsue");
  EXPECT_EQ(store.Put("hello, tissue"), sha);
  EXPECT_TRUE(store.Intact(sha));
}

TEST(BlobStoreTest, PartialBytesSurviveAndResume) {
  testing::TempDir dir("blobs");
  const std::string bytes = "0123456789abcdefghij";
  const auto entry = EntryOf("clip/a.png", bytes);
  {
    BlobStore store(dir.path());
    auto writer = store.OpenWriter(entry);
    writer->Append(0, std::string_view(bytes).substr(0, 8));
  }
  BlobStore reopened(dir.path());
  EXPECT_EQ(reopened.Committed(entry), 8);
  EXPECT_FALSE(reopened.Has(entry.sha256()));
  auto writer = reopened.OpenWriter(entry);
  EXPECT_EQ(writer->committed(), 8);
  EXPECT_EQ(CodeOf([&] { writer->Append(12, "x"); }), ErrorCode::kFailedPrecondition);
  writer->Append(4, std::string_view(bytes).substr(4, 8));  // re-sends bytes 4..8, adds 8..12
  EXPECT_EQ(writer->committed(), 12);
  writer->Append(12, std::string_view(bytes).substr(12));
  ASSERT_TRUE(writer->full());
  writer->Promote();
  EXPECT_TRUE(reopened.Has(entry.sha256()));
  EXPECT_EQ(testing::ReadBytes(reopened.PathOf(entry.sha256())), bytes);
  EXPECT_EQ(reopened.Committed(entry), entry.size());
}

// Found by bench/fault_campaign: a server killed between the last write and the rename left a full
// partial, which every later upload reported as committed and never promoted.
TEST(BlobStoreTest, AFullPartialLeftByACrashIsPromoted) {
  testing::TempDir dir("blobs");
  const std::string bytes = "0123456789abcdefghij";
  const auto entry = EntryOf("clip/a.png", bytes);
  BlobStore store(dir.path());
  EXPECT_FALSE(store.PromoteIfFull(entry));
  testing::WriteBytes(dir / ("partial/" + entry.sha256() + ".part"), bytes.substr(0, 8));
  EXPECT_FALSE(store.PromoteIfFull(entry));
  testing::WriteBytes(dir / ("partial/" + entry.sha256() + ".part"), bytes);
  EXPECT_EQ(store.Committed(entry), entry.size());
  EXPECT_FALSE(store.Has(entry.sha256()));
  EXPECT_TRUE(store.PromoteIfFull(entry));
  EXPECT_EQ(testing::ReadBytes(store.PathOf(entry.sha256())), bytes);
  EXPECT_FALSE(store.PromoteIfFull(entry)) << "no partial left to promote";
}

TEST(BlobStoreTest, WrongDigestDiscardsTheBytes) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  auto entry = EntryOf("x.bin", "expected content");
  auto writer = store.OpenWriter(entry);
  writer->Append(0, "different bytes!");
  EXPECT_EQ(CodeOf([&] { writer->Promote(); }), ErrorCode::kDataLoss);
  EXPECT_FALSE(store.Has(entry.sha256()));
  EXPECT_EQ(store.Committed(entry), 0);
  EXPECT_TRUE(std::filesystem::is_empty(dir / "partial"));
}

TEST(BlobStoreTest, DataPastTheDeclaredSizeIsRejected) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  auto writer = store.OpenWriter(EntryOf("x.bin", "abc"));
  EXPECT_EQ(CodeOf([&] { writer->Append(0, "abcd"); }), ErrorCode::kInvalidArgument);
}

TEST(BlobStoreTest, OneWriterPerContentAtATime) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  const auto entry = EntryOf("x.bin", "abc");
  auto writer = store.OpenWriter(entry);
  EXPECT_EQ(store.TryOpenWriter(entry), nullptr);
  EXPECT_EQ(CodeOf([&] { store.OpenWriter(entry); }), ErrorCode::kFailedPrecondition);
  writer.reset();
  EXPECT_NE(store.TryOpenWriter(entry), nullptr);
}

// A stream that waited for another to finish the same content opens a writer on a blob that now
// exists: it leaves no empty partial file behind (parallel submits of one clip left dozens).
TEST(BlobStoreTest, AWriterOnContentAlreadyStoredLeavesNoPartialFile) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  const auto entry = EntryOf("x.bin", "abc");
  store.Put("abc");
  { auto late = store.OpenWriter(entry); }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "partial" / (entry.sha256() + ".part")));
  EXPECT_TRUE(store.Has(entry.sha256()));
}

// Each tenant's upload goes into a partial of its own, so a digest that checks out says that tenant
// sent every byte (BlobHolders' proof): two tenants write the same content at once, a partial sent
// again for content already stored is kept for its resume, and its promotion replaces the blob.
TEST(BlobStoreTest, EachTenantUploadsIntoAPartialOfItsOwn) {
  testing::TempDir dir("blobs");
  BlobStore store(dir.path());
  const std::string bytes = "content two tenants have";
  const auto entry = EntryOf("x.bin", bytes);
  {
    auto a = store.OpenWriter(entry, "radiology");
    auto b = store.OpenWriter(entry, "oncology");
    EXPECT_EQ(store.TryOpenWriter(entry, std::chrono::milliseconds(0), "radiology"), nullptr);
    a->Append(0, bytes.substr(0, 7));
    b->Append(0, bytes.substr(0, 3));
  }
  EXPECT_EQ(store.Committed(entry, "radiology"), 7);
  EXPECT_EQ(store.Committed(entry, "oncology"), 3);
  EXPECT_EQ(store.Committed(entry), 0) << "the server's own partial is another";
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "partial" / (entry.sha256() + ".radiology.part")));
  std::map<std::string, std::int64_t> partials;
  for (const auto& file : store.Files()) {
    EXPECT_TRUE(file.partial);
    EXPECT_EQ(file.sha256, entry.sha256());
    partials[file.owner] = file.bytes;
  }
  EXPECT_EQ(partials, (std::map<std::string, std::int64_t>{{"oncology", 3}, {"radiology", 7}}));

  store.Put(bytes);  // someone else's upload completes the content
  EXPECT_EQ(store.Committed(entry, "oncology"), entry.size());
  EXPECT_EQ(store.PartialBytes(entry, "oncology"), 3);
  { auto resumed = store.OpenWriter(entry, "oncology"); }
  EXPECT_EQ(store.PartialBytes(entry, "oncology"), 3) << "a partial with bytes is kept for its resume";
  auto resumed = store.OpenWriter(entry, "oncology");
  resumed->Append(3, bytes.substr(3));
  resumed->Promote();
  resumed.reset();
  EXPECT_EQ(store.PartialBytes(entry, "oncology"), 0);
  EXPECT_EQ(testing::ReadBytes(store.PathOf(entry.sha256())), bytes);

  BlobStore::StoredFile radiology;
  for (const auto& file : store.Files()) {
    if (file.partial) radiology = file;
  }
  EXPECT_EQ(radiology.owner, "radiology");
  store.Remove(radiology);
  EXPECT_EQ(store.PartialBytes(entry, "radiology"), 0);
  EXPECT_TRUE(store.Has(entry.sha256())) << "removing a partial leaves the blob";
}

}  // namespace
}  // namespace endorecon::server
