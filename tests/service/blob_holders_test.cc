#include "server/blob_holders.h"

#include <gtest/gtest.h>

#include <string>

namespace endorecon::server {
namespace {

// Content no tenant holds is anyone's to name; content a tenant holds is another's only once that
// one holds it too; a content the store deleted is no one's any more.
TEST(BlobHoldersTest, ATenantNamesContentItHoldsOrThatNoTenantHolds) {
  const std::string x(64, 'a'), y(64, 'b'), z(64, 'c');
  BlobHolders holders;
  EXPECT_TRUE(holders.MayUse("radiology", x));
  holders.Add("radiology", x);
  EXPECT_TRUE(holders.MayUse("radiology", x));
  EXPECT_FALSE(holders.MayUse("oncology", x));
  EXPECT_FALSE(holders.MayUse("", x)) << "admins' tenant is a tenant like any other";
  holders.Add("oncology", x);
  holders.Add("oncology", x);  // twice is once
  EXPECT_TRUE(holders.MayUse("oncology", x));
  holders.Add("cardiology", x);
  EXPECT_TRUE(holders.MayUse("cardiology", x));
  EXPECT_FALSE(holders.MayUse("research", x));
  EXPECT_EQ(holders.size(), 1u);
  holders.Forget(x);
  EXPECT_TRUE(holders.MayUse("research", x));
  EXPECT_EQ(holders.size(), 0u);

  EXPECT_FALSE(holders.MayUse("radiology", "not a digest"));
  holders.Add("radiology", std::string(64, 'A'));  // not lowercase hex: not a digest, ignored
  EXPECT_EQ(holders.size(), 0u);

  v1::Job job;
  job.set_tenant("radiology");
  job.mutable_clip()->add_files()->set_sha256(x);
  job.mutable_result()->add_files()->set_sha256(y);
  job.mutable_checkpoint()->set_sha256(z);
  holders.AddJob(job);
  for (const auto& digest : {x, y, z}) EXPECT_FALSE(holders.MayUse("oncology", digest)) << digest;
  v1::Job expired = job;
  expired.set_tenant("oncology");
  expired.set_expired_unix_ms(1);
  holders.AddJob(expired);
  EXPECT_FALSE(holders.MayUse("oncology", x)) << "an expired job's files are gone: it holds nothing";
}

}  // namespace
}  // namespace endorecon::server
