#include "server/call_guard.h"

#include <spdlog/spdlog.h>

#include <cctype>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/transport_security.h"
#include "server/unix_time.h"

namespace endorecon::server {
namespace {

// gRPC's peer with its percent-escapes decoded: "ipv6:%5B::1%5D:39948" is "ipv6:[::1]:39948", as
// log collectors and people read addresses.
std::string PeerText(const std::string& peer) {
  std::string text;
  for (std::size_t i = 0; i < peer.size(); ++i) {
    if (peer[i] == '%' && i + 2 < peer.size() && std::isxdigit(static_cast<unsigned char>(peer[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(peer[i + 2]))) {
      text += static_cast<char>(std::stoi(peer.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      text += peer[i];
    }
  }
  return text;
}

std::string CertificateName(const grpc::ServerContext& context) {
  const auto auth = context.auth_context();
  if (!auth || !auth->IsPeerAuthenticated()) return "";
  const auto names = auth->FindPropertyValues("x509_common_name");
  return names.empty() ? "(no common name)" : std::string(names.front().data(), names.front().size());
}

std::string BearerToken(const grpc::ServerContext& context) {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("authorization");
  if (found == metadata.end()) {
    Fail(ErrorCode::kUnauthenticated,
         "no token: this server requires one (endorecon --token-file FILE or $ENDORECON_TOKEN; "
         "endorecon-worker serve --token-file FILE)");
  }
  const std::string_view value(found->second.data(), found->second.size());
  constexpr std::string_view kBearer = "Bearer ";
  if (value.substr(0, kBearer.size()) != kBearer)
    Fail(ErrorCode::kUnauthenticated, "malformed authorization header: expected 'Bearer <token>'");
  return std::string(value.substr(kBearer.size()));
}

// Transient outcomes (the caller went away, a timeout) are neither refusals nor worth a line.
bool Refused(const grpc::Status& status) {
  switch (status.error_code()) {
    case grpc::StatusCode::OK:
    case grpc::StatusCode::CANCELLED:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
    case grpc::StatusCode::UNAVAILABLE:
      return false;
    default:
      return true;
  }
}

// The status's name as the audit log and the metrics write it (gRPC's C++ API has none).
const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "UNKNOWN";
  }
}

}  // namespace

CallGuard::CallGuard(std::filesystem::path token_store, bool require_worker_certificate, AuditLog& audit,
                     Metrics& metrics, bool require_tokens)
    : token_store_path_(std::move(token_store)),
      require_worker_certificate_(require_worker_certificate),
      require_tokens_(require_tokens),
      audit_(audit),
      metrics_(metrics) {
  Refresh();
  serving_ = true;
  // At start a store that does not open stops the server, saying why (not a temporary fault).
  if (!open_failure_.empty()) {
    // The store's own check names another user's file already: the hint is not said twice.
    const std::string owner = open_failure_.find("chown") != std::string::npos
                                  ? ""
                                  : "owned by another user? chown it to the server's user; ";
    Fail(ErrorCode::kFailedPrecondition,
         open_failure_ + " (" + owner +
             "an empty file that `sqlite3 tokens.sqlite .backup` left where there was no store: remove it)");
  }
}

bool CallGuard::Refresh() { return Tokens() != nullptr; }

std::string CallGuard::OpenFailure() {
  std::lock_guard lock(mutex_);
  return open_failure_;
}

void CallGuard::PublishTokenExpiries() {
  TokenStore* tokens = Tokens();
  if (tokens == nullptr) return;
  std::vector<Metrics::ExpiringToken> expiring;
  for (const auto& record : tokens->List()) {
    if (record.revoked_unix_ms == 0 && record.expires_unix_ms != 0)
      expiring.push_back({record.name, RoleName(record.role), record.expires_unix_ms});
  }
  metrics_.SetTokenExpiries(expiring);
}

std::int64_t CallGuard::TokenRevokedAt(const std::string& name) {
  TokenStore* tokens = Tokens();
  if (tokens == nullptr || name.empty()) return 0;
  const std::int64_t now = NowUnixMs();
  const TokenRecord* latest = nullptr;
  const auto records = tokens->List();
  for (const auto& record : records) {
    if (record.name != name) continue;
    if (record.StateAt(now) == "active") return 0;
    if (!latest || record.created_unix_ms > latest->created_unix_ms) latest = &record;
  }
  return latest && latest->StateAt(now) == "revoked" ? latest->revoked_unix_ms : 0;
}

TokenStore* CallGuard::Tokens() {
  std::lock_guard lock(mutex_);
  if (enforcing_) return tokens_.get();
  const bool appeared = !tokens_ && std::filesystem::exists(token_store_path_);
  if (!tokens_ && !appeared) open_failure_.clear();  // none, or the one that did not open removed
  if (appeared) {
    // A store that appears but does not open (an empty file another user owns: `sqlite3
    // tokens.sqlite .backup` run as root where there was no store creates one) is logged and every
    // call refused until it opens; it threw out of the server's periodic work and aborted it (found
    // 2026-12-07).
    try {
      tokens_ = std::make_unique<TokenStore>(token_store_path_);
      open_failure_.clear();
    } catch (const Error& e) {
      if (open_failure_ != e.what() && serving_) {
        spdlog::error(
            "{}: {}; every call is refused until the token store opens (a file another user owns, or "
            "an empty one `sqlite3 tokens.sqlite .backup` left where there was no store: remove it)",
            ErrorCodeName(e.code()), e.what());
      }
      open_failure_ = e.what();
      return nullptr;
    }
  }
  // A store requires tokens once it holds one (revoked or not), never before: an empty one (made by
  // a failed `token create` of an older version, say) would lock every caller out.
  if (tokens_ && !tokens_->Empty()) {
    enforcing_ = true;
    spdlog::info("token store {} holds tokens: every call needs one from now on", token_store_path_.string());
  }
  return enforcing_ ? tokens_.get() : nullptr;
}

void CallGuard::AnnounceExpiry(grpc::ServerContext& context, const Call& call) {
  if (call.caller.token_expires_unix_ms == 0) return;
  context.AddInitialMetadata(kTokenExpiresHeader, std::to_string(call.caller.token_expires_unix_ms));
}

void CallGuard::Admit(const grpc::ServerContext& context, const Rpc& rpc, Call& call) {
  if (rpc.access == Access::kWorker && require_worker_certificate_ && CertificateName(context).empty()) {
    Fail(ErrorCode::kUnauthenticated,
         "the worker API requires a client certificate signed by the server's --tls-client-ca "
         "(endorecon-worker serve --tls-cert FILE --tls-key FILE)");
  }
  TokenStore* tokens = Tokens();
  if (!tokens) {
    const std::string failure = OpenFailure();
    if (!failure.empty())
      Fail(ErrorCode::kUnavailable,
           "the server's token store cannot be opened, so no call is admitted: " + failure);
    // A server started before its first token (a Kubernetes pod, whose tokens are made with kubectl
    // exec once it runs) served every caller until then (found 2026-12-07).
    if (require_tokens_) {
      Fail(ErrorCode::kUnauthenticated,
           "this server requires tokens (--require-tokens) and none has been created yet: its admin makes "
           "the first with `endorecon-server token create --role admin`");
    }
    call.caller = AnonymousPrincipal();
    return;
  }
  // A revoked or expired token that proved its secret is named in the refusal's audit line (it was
  // "-", and a leaked token's use could not be traced; found 2026-12-05).
  TokenRecord refused;
  try {
    const auto record = tokens->Verify(BearerToken(context), &refused);
    call.caller = Principal{record.name, record.role, record.tenant, false, record.expires_unix_ms};
  } catch (const Error&) {
    if (!refused.name.empty()) {
      call.caller = Principal{refused.name, refused.role, refused.tenant, false, refused.expires_unix_ms};
    }
    throw;
  }
  const Role role = call.caller.role;
  // The messages do not name the method: the caller knows it, and the CLI says which call it made
  // ("workers: ListWorkers: needs an admin token" said it twice).
  switch (rpc.access) {
    case Access::kJobs:
      if (role == Role::kWorker)
        Fail(ErrorCode::kPermissionDenied, "a worker token may use the worker API only");
      break;
    case Access::kAdmin:
      if (role != Role::kAdmin) Fail(ErrorCode::kPermissionDenied, "this call needs an admin token");
      break;
    case Access::kWorker:
      if (role != Role::kWorker) {
        Fail(ErrorCode::kPermissionDenied, std::string("the worker API needs a worker token, not ") +
                                               (role == Role::kAdmin ? "an " : "a ") + RoleName(role) +
                                               " token");
      }
      break;
  }
}

std::string AuditedJobId(const std::string& id) {
  const bool made_here = id.size() == 12 && id.find_first_not_of("0123456789abcdef") ==
                                                std::string::npos;  // lease_table.h, RandomId
  return id.empty() || made_here ? id : "(not a job id)";
}

void CallGuard::Record(const grpc::ServerContext& context, const Rpc& rpc, const Call& call,
                       const grpc::Status& status) {
  const bool refused = Refused(status);
  if (refused) metrics_.CallRefused(CodeName(status.error_code()));
  if (!rpc.writes && !call.wrote && !refused) return;
  const bool known = !call.caller.name.empty();
  AuditEntry entry{known ? call.caller.name : "-",
                   known && !call.caller.anonymous ? RoleName(call.caller.role) : "-",
                   call.caller.tenant,
                   rpc.method,
                   call.job_id,
                   CodeName(status.error_code()),
                   PeerText(context.peer()),
                   CertificateName(context),
                   rpc.subject};
  if (refused && !refusals_.Pass(entry, std::chrono::steady_clock::now())) return;
  audit_.Write(entry);
}

void CallGuard::FlushRefusals(bool all) {
  const auto now = std::chrono::steady_clock::now();
  for (const auto& entry : refusals_.TakeDue(all ? now + std::chrono::hours(1) : now)) audit_.Write(entry);
}

void CallGuard::RecordServerAction(const std::string& method, const std::string& job_id,
                                   const std::string& outcome, const std::string& subject) {
  audit_.Write({"server", "-", "", method, job_id, outcome, "", "", subject});
}

}  // namespace endorecon::server
