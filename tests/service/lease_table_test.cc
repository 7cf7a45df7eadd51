#include "server/lease_table.h"

#include <gtest/gtest.h>

namespace endorecon::server {
namespace {

using std::chrono::seconds;

TEST(LeaseTableTest, RenewedLeasesOutliveTheirFirstExpiry) {
  LeaseTable table(seconds(10));
  const auto t0 = Clock::now();
  const auto a = table.Grant("job-a", "worker-1", t0);
  const auto b = table.Grant("job-b", "worker-2", t0);
  EXPECT_NE(a.id, b.id);
  ASSERT_TRUE(table.Renew(a.id, t0 + seconds(8)).has_value());
  const auto expired = table.TakeExpired(t0 + seconds(12));
  ASSERT_EQ(expired.size(), 1u);
  EXPECT_EQ(expired[0].job_id, "job-b");
  EXPECT_EQ(expired[0].worker_id, "worker-2");
  EXPECT_TRUE(table.Find(a.id).has_value());
  EXPECT_FALSE(table.Find(b.id).has_value());
  EXPECT_EQ(table.TakeExpired(t0 + seconds(17)).size(), 0u);
  EXPECT_EQ(table.TakeExpired(t0 + seconds(18)).size(), 1u);
}

TEST(LeaseTableTest, AnExpiredLeaseCannotBeRenewed) {
  LeaseTable table(seconds(5));
  const auto t0 = Clock::now();
  const auto lease = table.Grant("job", "worker", t0);
  EXPECT_FALSE(table.Renew(lease.id, t0 + seconds(5)).has_value());
  EXPECT_FALSE(table.Renew("unknown", t0).has_value());
}

TEST(LeaseTableTest, ReleaseAndRestore) {
  LeaseTable table(seconds(5));
  const auto t0 = Clock::now();
  const auto lease = table.Grant("job", "worker", t0);
  EXPECT_TRUE(table.Release(lease.id));
  EXPECT_FALSE(table.Release(lease.id));
  table.Restore(lease.id, "job", "worker", t0 + seconds(100));
  const auto restored = table.Renew(lease.id, t0 + seconds(103));
  ASSERT_TRUE(restored.has_value());
  EXPECT_EQ(restored->job_id, "job");
  EXPECT_EQ(table.All().size(), 1u);
}

TEST(LeaseTableTest, RandomIdsAreHexOfTheRequestedLength) {
  const auto id = RandomId(6);
  EXPECT_EQ(id.size(), 12u);
  EXPECT_EQ(id.find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_NE(RandomId(6), id);
}

}  // namespace
}  // namespace endorecon::server
