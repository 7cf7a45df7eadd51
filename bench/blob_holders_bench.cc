// blob_holders_bench: what proof of possession (server/blob_holders.h) costs the server: memory per
// content held and the time of one Holds (each file of each upload query and submit), against a
// baseline measured in the same run: the plain way, a std::unordered_set of "tenant/hex digest"
// strings. Digests are random, so lookups miss the cache as a large store's would.
// Usage: blob_holders_bench [--contents N] [--tenants N]
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <unordered_set>
#include <vector>

#include "server/blob_holders.h"

namespace {

using Clock = std::chrono::steady_clock;

std::size_t Allocated() { return mallinfo2().uordblks + mallinfo2().hblkhd; }

// Nanoseconds per call of `holds` over every digest, three passes.
template <typename Holds>
double NsPerLookup(const std::vector<std::string>& digests, Holds&& holds, std::size_t& found) {
  const auto start = Clock::now();
  for (int pass = 0; pass < 3; ++pass) {
    for (std::size_t i = 0; i < digests.size(); ++i) found += holds(i, digests[i]);
  }
  return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / (3.0 * digests.size());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("blob_holders_bench: memory and lookup time of BlobHolders against a set of strings");
  std::size_t contents = 1'000'000;
  int tenants = 10;
  app.add_option("--contents", contents, "contents held");
  app.add_option("--tenants", tenants, "tenants they are spread over");
  CLI11_PARSE(app, argc, argv);

  std::mt19937_64 random(1);
  const char* hex = "0123456789abcdef";
  std::vector<std::string> digests(contents), names(static_cast<std::size_t>(tenants));
  for (auto& digest : digests) {
    digest.resize(64);
    for (auto& c : digest) c = hex[random() & 15];
  }
  for (int t = 0; t < tenants; ++t) names[static_cast<std::size_t>(t)] = "tenant-" + std::to_string(t);
  const auto tenant_of = [&](std::size_t i) -> const std::string& { return names[i % names.size()]; };

  auto before = Allocated();
  endorecon::server::BlobHolders holders;
  for (std::size_t i = 0; i < contents; ++i) holders.Add(tenant_of(i), digests[i]);
  const double holders_bytes = double(Allocated() - before) / double(contents);

  before = Allocated();
  std::unordered_set<std::string> strings;
  for (std::size_t i = 0; i < contents; ++i) strings.insert(tenant_of(i) + "/" + digests[i]);
  const double strings_bytes = double(Allocated() - before) / double(contents);

  std::size_t found = 0;
  const double holders_ns = NsPerLookup(
      digests, [&](std::size_t i, const std::string& digest) { return holders.Holds(tenant_of(i), digest); }, found);
  const double strings_ns = NsPerLookup(
      digests,
      [&](std::size_t i, const std::string& digest) { return strings.count(tenant_of(i) + "/" + digest) > 0; },
      found);
  if (found != 6 * contents) {
    std::fprintf(stderr, "lookups found %zu of %zu\n", found, 6 * contents);
    return 1;
  }
  std::printf("%zu contents over %d tenants\n", contents, tenants);
  std::printf("BlobHolders:          %6.1f bytes per content, %6.0f ns per Holds\n", holders_bytes, holders_ns);
  std::printf("unordered_set<string>: %5.1f bytes per content, %6.0f ns per lookup\n", strings_bytes, strings_ns);
  std::printf("ratio (BlobHolders / set): memory %.2f, time %.2f\n", holders_bytes / strings_bytes,
              holders_ns / strings_ns);
  return 0;
}
