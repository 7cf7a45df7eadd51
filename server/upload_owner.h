// Whose an upload is, for proof of possession (server/blob_holders.h): kept apart from the receiver
// so that the coordinator, which makes owners, does not include gRPC's stream headers.
#pragma once

#include <functional>
#include <set>
#include <string>

#include "endorecon/v1/files.pb.h"

namespace endorecon::server {

// The tenant an upload is for. Its bytes go to that tenant's partials (BlobStore), and a stored
// content the tenant does not hold (another tenant's, or no one's: BlobHolders) counts as not stored
// for it: its bytes are sent again, then checked against the digest, to show that it holds it. The
// default (no tenant, no functions) is the server's own partials, trusted with every stored content:
// a worker of every tenant, and tests.
struct UploadOwner {
  std::string tenant;
  // Of the contents of a manifest, those stored that the tenant has not shown it holds.
  std::function<std::set<std::string>(const v1::Manifest&)> unproven;
  // Told each content the tenant's partial held in full, digest checked, whether it was stored
  // before or not.
  std::function<void(const std::string& sha256)> proven;
  // Told once the upload stream ends, however it ends: what `proven` was told is made durable.
  std::function<void()> ended;
};

}  // namespace endorecon::server
