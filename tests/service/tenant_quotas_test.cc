#include "server/tenant_quotas.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

TEST(TenantQuotasTest, FileOverridesDefaultsPerTenantAndKey) {
  testing::TempDir dir("quotas");
  testing::WriteBytes(dir / "quotas.json",
                      R"({"radiology": {"max_jobs": 20}, "research": {"max_bytes": 0}})");
  const TenantQuotas quotas({5, 1000}, dir / "quotas.json");
  EXPECT_EQ(quotas.For("radiology").max_jobs, 20);
  EXPECT_EQ(quotas.For("radiology").max_bytes, 1000);
  EXPECT_EQ(quotas.For("research").max_bytes, 0);
  EXPECT_EQ(quotas.For("other").max_jobs, 5);
}

TEST(TenantQuotasTest, BadFilesNameWhatIsWrong) {
  testing::TempDir dir("quotas");
  for (const std::string bad : {R"([1])", R"({"x": {"max_jobs": -1}})", R"({"x": {"max_job": 1}})",
                                R"({"X": {"max_jobs": 1}})", R"({"x": {"max_jobs": "1"}})", "{"}) {
    testing::WriteBytes(dir / "quotas.json", bad);
    EXPECT_THROW(TenantQuotas({}, dir / "quotas.json"), Error) << bad;
  }
  try {
    testing::WriteBytes(dir / "quotas.json", R"({"x": {"max_job": 1}})");
    TenantQuotas({}, dir / "quotas.json");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.max_job"), std::string::npos) << e.what();
  }
  EXPECT_THROW(TenantQuotas({}, dir / "missing.json"), Error);
  // Found by tests/fuzz/quotas_fuzz.cc: a bad tenant name did not say which file it came from.
  try {
    testing::WriteBytes(dir / "quotas.json", R"({"ra`iology": {"max_jobs": 1}})");
    TenantQuotas({}, dir / "quotas.json");
    ADD_FAILURE() << "accepted a bad tenant name";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "quotas.json").string() + ": tenant 'ra`iology'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace endorecon::server
