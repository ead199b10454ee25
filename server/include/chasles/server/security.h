#pragma once
/// \file
/// Transport security and client authentication of chasles-server: TLS, mutual TLS (client
/// certificates) and bearer tokens with two roles.
///
/// Tokens file (`--tokens FILE`): one token per line as three whitespace-separated fields
/// `NAME ROLE TOKEN`; blank lines and lines whose first non-blank character is `#` are ignored.
///   - NAME: who holds the token (logged, and the key of the client's identity);
///   - ROLE: `plan` (planning and read-only calls, uploads, scene updates, benchmarks) or
///     `commit` (those and the workcell calls CreateWorkcell, CommitTrajectory, Release);
///   - TOKEN: at least 16 printable ASCII characters without spaces (`openssl rand -hex 32`).
/// Clients send `authorization: Bearer TOKEN` metadata. The health service (grpc.health.v1) and
/// server reflection need no token. Tokens are kept as SHA-256 digests, compared in constant
/// time, and never logged. Without TLS, tokens are accepted from loopback peers only (gRPC local
/// credentials): plaintext tokens are for local use and testing.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_context.h>
#include <grpcpp/support/status.h>

namespace chasles {

/// The server's security flags. All empty (the default) = plaintext, no authentication.
struct SecurityOptions {
  std::string tls_cert;       ///< --tls-cert: server certificate chain (PEM); enables TLS
  std::string tls_key;        ///< --tls-key: the certificate's private key (PEM, unencrypted)
  std::string tls_client_ca;  ///< --tls-client-ca: CA certificates (PEM) client certificates must
                              ///< chain to (mutual TLS); needs --tls-cert
  std::string tokens_file;    ///< --tokens: bearer tokens, `NAME ROLE TOKEN` per line (see above)

  bool tls() const { return !tls_cert.empty(); }
  bool mutual_tls() const { return !tls_client_ca.empty(); }
  bool tokens() const { return !tokens_file.empty(); }

  /// Checks the flag combination and reads every file named: it must exist, be readable and hold
  /// PEM of the right kind (certificates, an unencrypted private key that matches the
  /// certificate) or a valid tokens file.
  /// \throws Error(kInvalidArgument) naming the flag, the file and the rule broken.
  void Validate() const;
};

/// What a call needs: nothing (health, reflection), a token of any role, or a `commit` token.
enum class Permission { kOpen, kPlan, kCommit };

/// The permission an RPC needs. `rpc` is a method name of chasles.v1.Planning ("Plan") or a full
/// gRPC path ("/chasles.v1.Planning/Plan", "/grpc.health.v1.Health/Check"). Unknown methods need
/// kCommit (deny by default).
Permission RequiredPermission(std::string_view rpc);

/// Who is calling, for logs and the server's per-client scheduling.
struct ClientIdentity {
  std::string name;            ///< token name, else client certificate CN (or SAN), else peer address
  std::string role;            ///< "plan" or "commit" (from the token); empty without --tokens
  bool authenticated = false;  ///< by a known token or a verified client certificate
};

/// A call the credentials refused before any handler ran (for the request log and metrics).
struct AccessRefusal {
  std::string rpc;           ///< the gRPC path, e.g. "/chasles.v1.Planning/CommitTrajectory"
  grpc::StatusCode code{};   ///< UNAUTHENTICATED or PERMISSION_DENIED
  std::string message;       ///< the message the client got (never contains a token)
  std::string name;          ///< the token's name when the token was known, else ""
};

class TokenTable;  // the loaded tokens file (security.cc)

/// Authentication and authorisation of one server, built from its SecurityOptions. Immutable
/// after construction and thread-safe. The credentials it makes check every call's token in a
/// grpc::AuthMetadataProcessor before any handler runs; handlers call Authorize() as well (a
/// second check of the same rule) and IdentifyClient() to know the caller.
class AccessControl {
 public:
  /// Validates the options and loads the tokens. `on_refusal`, when set, is called (on a gRPC
  /// thread, possibly concurrently) for every call the credentials refuse.
  /// \throws Error(kInvalidArgument) as SecurityOptions::Validate.
  explicit AccessControl(const SecurityOptions& options,
                         std::function<void(const AccessRefusal&)> on_refusal = nullptr);
  ~AccessControl();

  /// TLS (mutual when a client CA is set), else gRPC local credentials when tokens are on
  /// (loopback peers only), else insecure; with tokens, an AuthMetadataProcessor is attached.
  std::shared_ptr<grpc::ServerCredentials> MakeServerCredentials() const;

  /// The caller of a running call: see ClientIdentity.
  ClientIdentity IdentifyClient(const grpc::ServerContextBase& context) const;

  /// OK when tokens are off or the call's token grants `rpc` (a method name, e.g. "Plan");
  /// UNAUTHENTICATED for a missing, malformed or unknown token; PERMISSION_DENIED naming the RPC
  /// and the role it needs when the token's role is not enough.
  grpc::Status Authorize(const grpc::ServerContextBase& context, std::string_view rpc) const;

  /// One line for the startup log, e.g. "TLS with client certificates, 3 bearer tokens".
  /// The same check for a request that is not a gRPC call (the viewer over HTTP): the value of
  /// its Authorization header (nullopt = none sent) for `rpc`.
  grpc::Status AuthorizeHeader(const std::optional<std::string>& authorization, std::string_view rpc) const;
  std::string Describe() const;

  bool tokens_enabled() const;
  std::size_t token_count() const;


 private:
  SecurityOptions options_;
  std::function<void(const AccessRefusal&)> on_refusal_;
  std::shared_ptr<const TokenTable> tokens_;  // shared with the AuthMetadataProcessor; null without --tokens
};

/// Convenience: AccessControl(options).MakeServerCredentials().
std::shared_ptr<grpc::ServerCredentials> MakeServerCredentials(const SecurityOptions& options);

/// True when `listen` (HOST:PORT) names a loopback host: 127.x.x.x, [::1] or localhost.
bool IsLoopbackAddress(std::string_view listen);

}  // namespace chasles
