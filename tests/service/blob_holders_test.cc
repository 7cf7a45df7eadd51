#include "server/blob_holders.h"

#include <gtest/gtest.h>

#include <string>

namespace endorecon::server {
namespace {

// A tenant names only content it holds; content another tenant holds is its too once it uploads it;
// a drop takes a tenant's holding back, and a content the store deleted is no one's any more.
TEST(BlobHoldersTest, ATenantNamesOnlyContentItHolds) {
  const std::string x(64, 'a'), y(64, 'b'), z(64, 'c');
  BlobHolders holders;
  EXPECT_FALSE(holders.Holds("radiology", x)) << "no one's content is no one's to name";
  holders.Add("radiology", x);
  EXPECT_TRUE(holders.Holds("radiology", x));
  EXPECT_FALSE(holders.Holds("oncology", x));
  EXPECT_FALSE(holders.Holds("", x)) << "admins' tenant is a tenant like any other";
  holders.Add("oncology", x);
  holders.Add("oncology", x);  // twice is once
  EXPECT_TRUE(holders.Holds("oncology", x));
  holders.Add("cardiology", x);
  EXPECT_TRUE(holders.Holds("cardiology", x));
  EXPECT_FALSE(holders.Holds("research", x));
  EXPECT_EQ(holders.size(), 1u);
  holders.Remove("radiology", x);  // the first holder goes: the others stay
  EXPECT_FALSE(holders.Holds("radiology", x));
  EXPECT_TRUE(holders.Holds("oncology", x));
  EXPECT_TRUE(holders.Holds("cardiology", x));
  holders.Remove("research", x);  // one that never held it
  holders.Remove("cardiology", x);
  holders.Remove("oncology", x);
  EXPECT_EQ(holders.size(), 0u) << "no holder left";
  holders.Add("radiology", x);
  holders.Add("oncology", x);
  holders.Forget(x);
  EXPECT_FALSE(holders.Holds("radiology", x));
  EXPECT_FALSE(holders.Holds("oncology", x));
  EXPECT_EQ(holders.size(), 0u);

  EXPECT_FALSE(holders.Holds("radiology", "not a digest"));
  holders.Add("radiology", std::string(64, 'A'));  // not lowercase hex: not a digest, ignored
  EXPECT_EQ(holders.size(), 0u);

  v1::Job job;
  job.set_tenant("radiology");
  job.mutable_clip()->add_files()->set_sha256(x);
  job.mutable_result()->add_files()->set_sha256(y);
  job.mutable_checkpoint()->set_sha256(z);
  holders.AddJob(job);
  for (const auto& digest : {x, y, z}) EXPECT_FALSE(holders.Holds("oncology", digest)) << digest;
  v1::Job expired = job;
  expired.set_tenant("oncology");
  expired.set_expired_unix_ms(1);
  holders.AddJob(expired);
  EXPECT_FALSE(holders.Holds("oncology", x)) << "an expired job's files are gone: it holds nothing";
}

}  // namespace
}  // namespace endorecon::server
