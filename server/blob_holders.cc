#include "server/blob_holders.h"

#include <algorithm>
#include <cstring>
#include <optional>

#include "common/manifest.h"

namespace endorecon::server {
namespace {

int HexValue(char c) { return c <= '9' ? c - '0' : c - 'a' + 10; }

// The 32 bytes of a digest kept as 64 lowercase hex characters (IsSha256Hex); nullopt otherwise.
std::optional<std::array<std::uint8_t, 32>> ParseDigest(const std::string& sha256) {
  if (!IsSha256Hex(sha256)) return std::nullopt;
  std::array<std::uint8_t, 32> digest{};
  for (std::size_t i = 0; i < digest.size(); ++i)
    digest[i] = static_cast<std::uint8_t>(HexValue(sha256[2 * i]) * 16 + HexValue(sha256[2 * i + 1]));
  return digest;
}

}  // namespace

std::size_t BlobHolders::DigestHash::operator()(const Digest& digest) const {
  std::size_t hash = 0;  // a digest's bytes are uniform already
  std::memcpy(&hash, digest.data(), sizeof hash);
  return hash;
}

std::uint32_t BlobHolders::TenantIndex(const std::string& tenant) {
  return tenant_index_.try_emplace(tenant, static_cast<std::uint32_t>(tenant_index_.size())).first->second;
}

void BlobHolders::Add(const std::string& tenant, const std::string& sha256) {
  const auto digest = ParseDigest(sha256);
  if (!digest) return;
  const auto index = TenantIndex(tenant);
  const auto [found, added] = holders_.try_emplace(*digest, Holders{index, {}});
  if (added) return;
  auto& holders = found->second;
  if (holders.first == index ||
      std::find(holders.more.begin(), holders.more.end(), index) != holders.more.end())
    return;
  holders.more.push_back(index);
}

void BlobHolders::AddFiles(const std::string& tenant, const v1::Manifest& files) {
  for (const auto& file : files.files()) Add(tenant, file.sha256());
}

void BlobHolders::AddJob(const v1::Job& job) {
  if (job.expired_unix_ms() > 0) return;
  AddFiles(job.tenant(), job.clip());
  AddFiles(job.tenant(), job.result());
  if (!job.checkpoint().sha256().empty()) Add(job.tenant(), job.checkpoint().sha256());
}

bool BlobHolders::Holds(const std::string& tenant, const std::string& sha256) const {
  const auto digest = ParseDigest(sha256);
  if (!digest) return false;
  const auto found = holders_.find(*digest);
  if (found == holders_.end()) return false;
  const auto index = tenant_index_.find(tenant);
  if (index == tenant_index_.end()) return false;
  const auto& holders = found->second;
  return holders.first == index->second ||
         std::find(holders.more.begin(), holders.more.end(), index->second) != holders.more.end();
}

void BlobHolders::Remove(const std::string& tenant, const std::string& sha256) {
  const auto digest = ParseDigest(sha256);
  const auto index = tenant_index_.find(tenant);
  if (!digest || index == tenant_index_.end()) return;
  const auto found = holders_.find(*digest);
  if (found == holders_.end()) return;
  auto& holders = found->second;
  std::erase(holders.more, index->second);
  if (holders.first != index->second) return;
  if (holders.more.empty()) {
    holders_.erase(found);
    return;
  }
  holders.first = holders.more.back();
  holders.more.pop_back();
}

void BlobHolders::Forget(const std::string& sha256) {
  if (const auto digest = ParseDigest(sha256)) holders_.erase(*digest);
}

}  // namespace endorecon::server
