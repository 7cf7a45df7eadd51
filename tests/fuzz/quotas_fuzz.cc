// The per-tenant quota file (`endorecon-server --quotas FILE`, server::TenantQuotas). Accepted
// quotas are never negative.
#include "server/tenant_quotas.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto path = fuzz::WriteInput("quotas.json", fuzz::Bytes(data, size));
  server::TenantQuotas quotas;
  if (!fuzz::Accepts(
          [&] {
            quotas = server::TenantQuotas({3, 0}, path);
          },
          {ErrorCode::kInvalidArgument}, path.string())) {
    return 0;
  }
  for (const char* tenant : {"radiology", "research", "a", ""}) {
    const auto quota = quotas.For(tenant);
    if (quota.max_jobs < 0 || quota.max_bytes < 0) fuzz::Broken("accepted a negative quota");
  }
  return 0;
}
