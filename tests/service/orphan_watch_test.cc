#include "server/orphan_watch.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <limits>
#include <string>

#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

using FileTime = std::filesystem::file_time_type;
constexpr std::int64_t kHour = 3'600'000;

BlobStore::StoredFile Orphan(const std::string& name, FileTime written) {
  BlobStore::StoredFile file;
  file.path = "/data/blobs/" + name;
  file.sha256 = name;
  file.bytes = 10;
  file.written = written;
  return file;
}

RetentionPlan PlanOf(std::initializer_list<BlobStore::StoredFile> orphans) {
  RetentionPlan plan;
  plan.orphans = orphans;
  return plan;
}

// An orphan goes once last written AND first found no job's --orphan-hours ago; when each was first
// found outlives the watch (a restart): with the hours counted from each start, a server restarted
// more often than --orphan-hours never deleted one (found 2026-12-07).
TEST(OrphanWatchTest, AnOrphanGoesOnceFoundSoTheHoursAgoAcrossARestart) {
  testing::TempDir dir("orphans");
  const auto file = dir / "orphans.json";
  const auto long_ago = FileTime::clock::now() - std::chrono::hours(72);
  const std::int64_t t0 = 1'765'000'000'000;
  const auto cutoff_at = [&](std::int64_t now) {
    return OrphanCutoff{FileTime::clock::now() - std::chrono::hours(24), now - 24 * kHour};
  };
  {
    OrphanWatch watch;
    watch.KeepIn(file);
    auto plan = PlanOf({Orphan("restored", long_ago), Orphan("fresh", FileTime::clock::now())});
    watch.Sift(plan, cutoff_at(t0), t0);
    EXPECT_TRUE(plan.orphans.empty()) << "an old file first found now waits";
    EXPECT_EQ(plan.orphans_waiting, 2);
    EXPECT_EQ(plan.orphan_bytes, 0);
  }
  ASSERT_TRUE(std::filesystem::exists(file));
  OrphanWatch restarted;
  restarted.KeepIn(file);
  auto plan = PlanOf({Orphan("restored", long_ago), Orphan("fresh", FileTime::clock::now())});
  restarted.Sift(plan, cutoff_at(t0 + 23 * kHour), t0 + 23 * kHour);
  EXPECT_TRUE(plan.orphans.empty());
  plan = PlanOf({Orphan("restored", long_ago), Orphan("fresh", FileTime::clock::now())});
  restarted.Sift(plan, cutoff_at(t0 + 25 * kHour), t0 + 25 * kHour);
  ASSERT_EQ(plan.orphans.size(), 1u) << "found 25 h ago, though the watch was made 2 h ago";
  EXPECT_EQ(plan.orphans[0].sha256, "restored");
  EXPECT_EQ(plan.orphan_bytes, 10);
  EXPECT_EQ(plan.orphans_waiting, 1) << "found long enough ago, but written now";
  // The file due is deleted next: orphans.json forgets it now (it listed it until the next check).
  const auto kept = testing::ReadBytes(file);
  EXPECT_EQ(kept.find("restored"), std::string::npos) << kept;
  EXPECT_NE(kept.find("fresh"), std::string::npos) << kept;
}

// A file that became a job's (or was deleted) is forgotten: no job's again later, it is found anew.
TEST(OrphanWatchTest, AFileNoLongerAnOrphanIsForgotten) {
  testing::TempDir dir("orphans");
  const auto long_ago = FileTime::clock::now() - std::chrono::hours(72);
  OrphanWatch watch;
  watch.KeepIn(dir / "orphans.json");
  auto plan = PlanOf({Orphan("a", long_ago), Orphan("b", long_ago)});
  watch.Sift(plan, {}, 0);
  plan = PlanOf({Orphan("b", long_ago)});  // a: a job's now
  watch.Sift(plan, {}, 0);
  plan = PlanOf({Orphan("a", long_ago), Orphan("b", long_ago)});
  watch.Sift(plan, {FileTime::clock::now(), 1}, 5);
  ASSERT_EQ(plan.orphans.size(), 1u);
  EXPECT_EQ(plan.orphans[0].sha256, "b") << "a, found anew at 5, is not due at 1";
  const auto text = testing::ReadBytes(dir / "orphans.json");
  EXPECT_NE(text.find("\"found_unix_ms\": 5"), std::string::npos) << text;
}

// Keys are paths in the data folder: a server started with the folder spelled otherwise (a unit file's
// absolute path, a shell's ./d) found every file anew, so restarts so spelled never deleted one; and
// files an upload brought are found while it does, so once it is given up they go --orphan-hours
// after they arrived, not that long after (found 2026-12-07).
TEST(OrphanWatchTest, APathIsTheSameWhateverTheFolderIsCalledAndUploadsAreFoundWhileTheyWait) {
  testing::TempDir dir("orphans");
  const auto long_ago = FileTime::clock::now() - std::chrono::hours(72);
  const auto in = [&](const std::filesystem::path& root, const std::string& name) {
    auto file = Orphan(name, long_ago);
    file.path = root / "blobs" / "ab" / name;
    return file;
  };
  {
    OrphanWatch watch;
    watch.KeepIn(dir / "orphans.json");
    RetentionPlan plan;
    plan.orphans = {in(dir.path(), "left")};
    plan.uploading = {in(dir.path(), "uploading")};
    watch.Sift(plan, {}, 100);
  }
  EXPECT_NE(testing::ReadBytes(dir / "orphans.json").find("\"blobs/ab/left\""), std::string::npos);
  OrphanWatch respelled;
  const auto other = dir.path() / ".";  // the same folder, spelled otherwise
  respelled.KeepIn(other / "orphans.json");
  RetentionPlan plan;
  plan.orphans = {in(other, "left"), in(other, "uploading")};  // the upload given up
  respelled.Sift(plan, {FileTime::clock::now(), 101}, 5000);
  EXPECT_EQ(plan.orphans.size(), 2u) << "both found at 100, before 101";
}

// A file that cannot be read is left aside: every orphan is found anew (later deletion, never
// earlier); the dry run's watch reads and never writes.
TEST(OrphanWatchTest, AnUnreadableFileIsLeftAsideAndTheDryRunWritesNothing) {
  testing::TempDir dir("orphans");
  const auto file = dir / "orphans.json";
  testing::WriteBytes(file, "{\"orphans\": [{\"path\": ");
  OrphanWatch watch;
  watch.KeepIn(file);
  auto plan = PlanOf({Orphan("a", FileTime::clock::now() - std::chrono::hours(72))});
  watch.Sift(plan, {FileTime::clock::now(), 100}, 100);
  EXPECT_TRUE(plan.orphans.empty());
  EXPECT_NE(testing::ReadBytes(file).find("\"found_unix_ms\": 100"), std::string::npos);

  OrphanWatch dry;
  dry.ReadFrom(file);
  plan = PlanOf({Orphan("b", FileTime::clock::now() - std::chrono::hours(72))});
  dry.Sift(plan, {FileTime::clock::now(), std::numeric_limits<std::int64_t>::max()}, 200);
  EXPECT_EQ(plan.orphans.size(), 1u);
  EXPECT_EQ(testing::ReadBytes(file).find("200"), std::string::npos) << "the dry run wrote";
}

}  // namespace
}  // namespace endorecon::server
