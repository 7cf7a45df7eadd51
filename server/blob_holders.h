// Which tenants have shown that they hold which stored content (proof of possession). The store keeps
// each content once, whoever sent it, so without this a tenant that learned a digest of another
// tenant's file (a log line, a shared listing) could name it in a job, skip its upload, and get a
// reconstruction of the other tenant's patient back. A tenant holds a content when one of its jobs
// names it (clip, checkpoint, result) or when its own upload sent every byte of it (digest checked);
// a worker token scoped to a tenant uploads for that tenant. Any other stored content (another
// tenant's, or one no tenant holds: a worker's results before its job takes them, an earlier
// checkpoint) is the tenant's to name only after it uploads it too. The server's own (a PACS
// retrieval) and a worker of every tenant's are trusted, and become their job's tenant's.
//
// Kept in memory: rebuilt at start from the jobs not expired and the uploads not yet submitted that
// were proven (UploadLedger). A content is forgotten when the store deletes it. A worker's proof of
// a content no job names yet, or a tenant's of one its expired job named, is not kept across a
// restart: it uploads the content again, the safe side. About 108 bytes per content held, and 0.35 us
// per Holds at a million contents (bench/blob_holders_bench, docs/benchmarks.md). Not thread-safe:
// the coordinator holds its lock.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "endorecon/v1/job.pb.h"

namespace endorecon::server {

class BlobHolders {
 public:
  // `tenant` holds the content `sha256` (a 64-hex digest; anything else is ignored).
  void Add(const std::string& tenant, const std::string& sha256);
  void AddFiles(const std::string& tenant, const v1::Manifest& files);
  // The job's tenant holds its clip, checkpoint and result; an expired job's are left out.
  void AddJob(const v1::Job& job);
  // Whether `tenant` holds the content, so that it may name it in a job.
  bool Holds(const std::string& tenant, const std::string& sha256) const;
  // Whether a tenant other than `tenant` holds the content.
  bool HeldByAnother(const std::string& tenant, const std::string& sha256) const;
  // `tenant` gave its upload of the content up (and no job of it names the content).
  void Remove(const std::string& tenant, const std::string& sha256);
  // The store deleted the content: no one holds it any more.
  void Forget(const std::string& sha256);
  // How many contents some tenant holds.
  std::size_t size() const { return holders_.size(); }

 private:
  using Digest = std::array<std::uint8_t, 32>;
  struct DigestHash {
    std::size_t operator()(const Digest& digest) const;
  };
  // Most content has one holder: it is kept in place, any others beside it.
  struct Holders {
    std::uint32_t first = 0;
    std::vector<std::uint32_t> more;
  };
  std::uint32_t TenantIndex(const std::string& tenant);

  std::unordered_map<Digest, Holders, DigestHash> holders_;
  std::unordered_map<std::string, std::uint32_t> tenant_index_;  // tenants interned: 4 bytes a holder
};

}  // namespace endorecon::server
