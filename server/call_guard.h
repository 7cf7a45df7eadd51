// The one gate every RPC handler goes through: who is calling (bearer token, client certificate),
// whether that caller may use this API, the handler itself with its errors turned into statuses,
// and the audit line. A new RPC gets all of it by wrapping its body:
//
//   return guard_.Run(context, {"Submit", Access::kJobs, kWrites}, [&](Call& call) {
//     *job = coordinator_.Submit(*request, call.caller);
//     call.job_id = job->id();
//     return grpc::Status::OK;
//   });
//
// Refusals: no token, a malformed, unknown or revoked one, or (worker API, when the server has a
// client CA) no verified client certificate: UNAUTHENTICATED. A client token on the worker API, a
// worker token on the job API, a non-admin on an admin call: PERMISSION_DENIED. Without a token
// store every caller is the anonymous principal and may use every API (loopback use); the store is
// picked up within a second of its first token being created, without a restart.
#pragma once

#include <grpcpp/server_context.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "common/grpc_status.h"
#include "server/audit_log.h"
#include "server/metrics.h"
#include "server/principal.h"
#include "server/refusal_pacer.h"
#include "server/token_store.h"

namespace endorecon::server {

enum class Access {
  kJobs,    // the job API: client and admin tokens
  kAdmin,   // admin tokens only (the worker list)
  kWorker,  // the worker API: worker tokens, and a client certificate when the server has a client CA
};

inline constexpr bool kWrites = true;
inline constexpr bool kReads = false;

// A job id as the audit log records it: an id of the form the server makes (12 hex digits) as it is,
// anything else as "(not a job id)". A caller's "status Doe^John-MRN-12345" put a patient's name in
// the log, and an id of 120,000 bytes a line as long (found 2026-12-06).
std::string AuditedJobId(const std::string& id);

// What a handler is, for the gate and the audit log.
struct Rpc {
  const char* method;
  Access access;
  bool writes;         // audited whatever its outcome; reads only when refused
  std::string job_id;  // the job it concerns when the request names one
  std::string subject;  // what else it acts on, for the audit log (a worker's id: Drain)
};

// The call as the handler sees it.
struct Call {
  Principal caller;
  std::string job_id;  // set by a handler whose job is known only inside (Submit, Lease, Complete)
  bool wrote = false;  // set by a read whose outcome changed something after all (a granted lease)
};

class CallGuard {
 public:
  // `token_store`: where the token store is or will be; `require_worker_certificate`: the server
  // has a client CA.
  // `require_tokens`: a call is refused while the store holds no token (--require-tokens), rather
  // than admitted as anonymous.
  CallGuard(std::filesystem::path token_store, bool require_worker_certificate, AuditLog& audit,
            Metrics& metrics, bool require_tokens = false);

  template <typename Body>
  grpc::Status Run(grpc::ServerContext* context, const Rpc& rpc, Body&& body) {
    const auto start = std::chrono::steady_clock::now();
    Call call;
    call.job_id = AuditedJobId(rpc.job_id);
    const grpc::Status status = GuardStatus([&] {
      Admit(*context, rpc, call);
      AnnounceExpiry(*context, call);
      return body(call);
    });
    Record(*context, rpc, call, status);
    metrics_.CallHandled(rpc.method,
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return status;
  }

  // Opens the token store once its file exists (at start, and from the server's maintenance
  // thread). Returns whether tokens are required now.
  bool Refresh();
  // Sets the token expiry gauges (Metrics::SetTokenExpiries) from the token store, if there is one:
  // the maintenance thread's, once a minute (an alert warns days ahead).
  void PublishTokenExpiries();
  // When the token labelled `name` was revoked (Unix ms; its latest holder of the label), 0 when a
  // token of that label is active, or none is known, or the latest one lapsed otherwise (expired).
  std::int64_t TokenRevokedAt(const std::string& name);
  // Audits something the server did on its own (retention, PACS retrievals and sends), as principal
  // "server"; `subject` names what it acted with (a PACS's name), never patient data.
  void RecordServerAction(const std::string& method, const std::string& job_id, const std::string& outcome,
                          const std::string& subject = "");
  // Writes the audit lines owed for refusals held back (RefusalPacer): the maintenance thread's, each
  // second, and at shutdown with `all` (every count held back, whatever its age).
  void FlushRefusals(bool all = false);

  // Fills call.caller, then throws Error(kUnauthenticated / kPermissionDenied) unless it may call `rpc`.
  // Run admits every call at its start; a long stream calls it again now and then, so a token
  // revoked or expired meanwhile ends the stream (its caller reopens it with its current token).
  void Admit(const grpc::ServerContext& context, const Rpc& rpc, Call& call);

  // Why a token store that exists does not open, every call being refused meanwhile; "" when it opens
  // or there is none.
  std::string OpenFailure();

 private:
  // Tells a caller whose token expires when: initial metadata kTokenExpiresHeader (Unix ms), read by
  // every client's channel (common/transport_security.h), which warns a week ahead.
  static void AnnounceExpiry(grpc::ServerContext& context, const Call& call);
  TokenStore* Tokens();
  void Record(const grpc::ServerContext& context, const Rpc& rpc, const Call& call,
              const grpc::Status& status);

  std::filesystem::path token_store_path_;
  bool require_worker_certificate_;
  bool require_tokens_;
  AuditLog& audit_;
  Metrics& metrics_;
  RefusalPacer refusals_{std::chrono::seconds(10), 5};  // up to 5 lines alike each 10 s
  std::mutex mutex_;
  std::unique_ptr<TokenStore> tokens_;
  bool enforcing_ = false;  // the store holds a token: from then on every call needs one
  // Why a token store that exists could not be opened (empty when it was, or there is none): every
  // call is refused meanwhile, and the periodic work goes on.
  std::string open_failure_;
  bool serving_ = false;  // past the constructor: a failure to open is logged (at start it is thrown)
};

}  // namespace endorecon::server
