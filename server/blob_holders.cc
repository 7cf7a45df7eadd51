#include "server/blob_holders.h"

#include <algorithm>
#include <cstring>
#include <optional>

namespace endorecon::server {
namespace {

// A digest's 32 bytes from its 64 lowercase hex characters (as IsSha256Hex checks them); nullopt for
// anything else. One pass with a table: it runs for every file of every upload query and submit.
std::optional<std::array<std::uint8_t, 32>> ParseDigest(const std::string& sha256) {
  static const auto kValue = [] {
    std::array<std::int8_t, 256> value{};
    value.fill(-1);
    for (int c = '0'; c <= '9'; ++c) value[static_cast<std::size_t>(c)] = static_cast<std::int8_t>(c - '0');
    for (int c = 'a'; c <= 'f'; ++c)
      value[static_cast<std::size_t>(c)] = static_cast<std::int8_t>(c - 'a' + 10);
    return value;
  }();
  if (sha256.size() != 64) return std::nullopt;
  std::array<std::uint8_t, 32> digest{};
  for (std::size_t i = 0; i < digest.size(); ++i) {
    const int high = kValue[static_cast<unsigned char>(sha256[2 * i])];
    const int low = kValue[static_cast<unsigned char>(sha256[2 * i + 1])];
    if ((high | low) < 0) return std::nullopt;
    digest[i] = static_cast<std::uint8_t>(high * 16 + low);
  }
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
  const auto index = tenant_index_.find(tenant);
  if (index == tenant_index_.end()) return false;
  const auto digest = ParseDigest(sha256);
  if (!digest) return false;
  const auto found = holders_.find(*digest);
  if (found == holders_.end()) return false;
  const auto& holders = found->second;
  return holders.first == index->second ||
         std::find(holders.more.begin(), holders.more.end(), index->second) != holders.more.end();
}

bool BlobHolders::HeldByAnother(const std::string& tenant, const std::string& sha256) const {
  const auto digest = ParseDigest(sha256);
  if (!digest) return false;
  const auto found = holders_.find(*digest);
  if (found == holders_.end()) return false;
  const auto index = tenant_index_.find(tenant);
  const std::size_t holders = 1 + found->second.more.size();
  return index == tenant_index_.end() || holders > 1 || found->second.first != index->second;
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
