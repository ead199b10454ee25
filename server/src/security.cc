#include "chasles/server/security.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include <grpc/grpc_security_constants.h>
#include <grpcpp/security/auth_metadata_processor.h>
#include <openssl/crypto.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include "chasles/robot/error.h"

namespace chasles {

namespace {

constexpr std::size_t kMinTokenLength = 16;
constexpr std::string_view kPlanningService = "/chasles.v1.Planning/";

// --- files and PEM -------------------------------------------------------------------------------

std::string Quoted(const std::string& text) { return "'" + text + "'"; }

std::string ReadFile(const char* flag, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    ThrowInvalid(std::string(flag) + " " + Quoted(path) + " cannot be read: " + std::strerror(errno));
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

struct BioDeleter {
  void operator()(BIO* bio) const { BIO_free(bio); }
};
struct X509Deleter {
  void operator()(X509* cert) const { X509_free(cert); }
};
struct KeyDeleter {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};
using X509Ptr = std::unique_ptr<X509, X509Deleter>;

std::unique_ptr<BIO, BioDeleter> MemoryBio(const std::string& text) {
  return std::unique_ptr<BIO, BioDeleter>(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

/// A password callback that refuses: an encrypted key fails instead of prompting on the terminal.
extern "C" int NoPassword(char*, int, int, void*) { return -1; }

/// The certificates of a PEM file, in order; throws when there is none.
std::vector<X509Ptr> ReadCertificates(const char* flag, const std::string& path) {
  const std::string text = ReadFile(flag, path);
  auto bio = MemoryBio(text);
  std::vector<X509Ptr> certs;
  while (X509* cert = PEM_read_bio_X509(bio.get(), nullptr, NoPassword, nullptr)) certs.emplace_back(cert);
  ERR_clear_error();  // the read past the last certificate leaves an error on the queue
  if (certs.empty()) {
    ThrowInvalid(std::string(flag) + " " + Quoted(path) +
                 " holds no PEM certificate (expected a '-----BEGIN CERTIFICATE-----' block)");
  }
  return certs;
}

void CheckKeyMatches(const SecurityOptions& options) {
  const std::vector<X509Ptr> certs = ReadCertificates("--tls-cert", options.tls_cert);
  const std::string text = ReadFile("--tls-key", options.tls_key);
  auto bio = MemoryBio(text);
  std::unique_ptr<EVP_PKEY, KeyDeleter> key(PEM_read_bio_PrivateKey(bio.get(), nullptr, NoPassword, nullptr));
  ERR_clear_error();
  if (!key) {
    ThrowInvalid("--tls-key " + Quoted(options.tls_key) +
                 " holds no unencrypted PEM private key (expected a '-----BEGIN PRIVATE KEY-----' or "
                 "'-----BEGIN EC/RSA PRIVATE KEY-----' block without a passphrase)");
  }
  const bool matches = X509_check_private_key(certs.front().get(), key.get()) == 1;
  ERR_clear_error();
  if (!matches) {
    ThrowInvalid("--tls-key " + Quoted(options.tls_key) + " is not the private key of the first certificate in --tls-cert " +
                 Quoted(options.tls_cert));
  }
}

/// The TLS flags: both or neither of cert and key, the key matches, the client CA holds
/// certificates.
void ValidateTls(const SecurityOptions& options) {
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    ThrowInvalid(options.tls_cert.empty() ? "--tls-key is set but --tls-cert is not: TLS needs both (PEM files)"
                                          : "--tls-cert is set but --tls-key is not: TLS needs both (PEM files)");
  }
  if (options.mutual_tls() && !options.tls()) {
    ThrowInvalid("--tls-client-ca " + Quoted(options.tls_client_ca) +
                 " needs --tls-cert and --tls-key: mutual TLS is TLS with client certificates");
  }
  if (!options.tls()) return;
  CheckKeyMatches(options);
  if (options.mutual_tls()) ReadCertificates("--tls-client-ca", options.tls_client_ca);
}

// --- tokens ----------------------------------------------------------------------------------------

using Digest = std::array<unsigned char, 32>;

Digest Sha256(std::string_view text) {
  Digest digest{};
  unsigned int size = 0;
  if (EVP_Digest(text.data(), text.size(), digest.data(), &size, EVP_sha256(), nullptr) != 1 || size != digest.size()) {
    throw std::runtime_error("SHA-256 of a bearer token failed (OpenSSL EVP_Digest)");
  }
  return digest;
}

const char* RoleName(Permission role) { return role == Permission::kCommit ? "commit" : "plan"; }

std::string_view Trim(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return text;
}

bool EqualsIgnoreCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

/// The loaded tokens file: names, roles and SHA-256 digests of the tokens (never the tokens).
class TokenTable {
 public:
  struct Entry {
    std::string name;
    Permission role = Permission::kPlan;
    Digest digest{};
  };

  static std::shared_ptr<const TokenTable> Load(const std::string& path) {
    const std::string text = ReadFile("--tokens", path);
    auto table = std::make_shared<TokenTable>();
    std::vector<int> lines;  // line of each entry, for messages about repeats
    std::istringstream in(text);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      const std::string_view content = Trim(line);
      if (content.empty() || content.front() == '#') continue;
      const std::string where = "--tokens " + Quoted(path) + " line " + std::to_string(number);
      std::istringstream fields{std::string(content)};
      std::vector<std::string> parts;
      for (std::string part; fields >> part;) parts.push_back(part);
      if (parts.size() != 3) {
        // The line is not echoed: it may hold a token.
        ThrowInvalid(where + " has " + std::to_string(parts.size()) +
                     " fields; expected 3: NAME ROLE TOKEN (ROLE is 'plan' or 'commit')");
      }
      Entry entry;
      entry.name = parts[0];
      if (parts[1] == "plan") {
        entry.role = Permission::kPlan;
      } else if (parts[1] == "commit") {
        entry.role = Permission::kCommit;
      } else {
        ThrowInvalid(where + ": role " + Quoted(parts[1]) + " of " + Quoted(entry.name) +
                     " must be 'plan' or 'commit'");
      }
      const std::string& token = parts[2];
      if (token.size() < kMinTokenLength) {
        ThrowInvalid(where + ": the token of " + Quoted(entry.name) + " has " + std::to_string(token.size()) +
                     " characters; it must have at least " + std::to_string(kMinTokenLength) +
                     " (e.g. from 'openssl rand -hex 32')");
      }
      if (!std::all_of(token.begin(), token.end(), [](char c) { return c >= 0x21 && c <= 0x7e; })) {
        ThrowInvalid(where + ": the token of " + Quoted(entry.name) +
                     " must be printable ASCII without spaces (it travels in gRPC metadata)");
      }
      entry.digest = Sha256(token);
      for (std::size_t i = 0; i < table->entries_.size(); ++i) {
        if (table->entries_[i].digest == entry.digest) {
          ThrowInvalid(where + ": the token of " + Quoted(entry.name) + " repeats the token of " +
                       Quoted(table->entries_[i].name) + " (line " + std::to_string(lines[i]) +
                       "); every token must be different");
        }
      }
      table->entries_.push_back(std::move(entry));
      lines.push_back(number);
    }
    if (table->entries_.empty()) {
      ThrowInvalid("--tokens " + Quoted(path) +
                   " holds no tokens (expected lines 'NAME ROLE TOKEN'); every call would be refused");
    }
    return table;
  }

  /// The entry of `token`, or null. Every entry is compared, each in constant time, so the time
  /// taken does not depend on which entry (if any) matches or on how much of it matches.
  const Entry* Find(std::string_view token) const {
    const Digest digest = Sha256(token);
    const Entry* found = nullptr;
    for (const Entry& entry : entries_) {
      const bool equal = CRYPTO_memcmp(entry.digest.data(), digest.data(), digest.size()) == 0;
      found = equal ? &entry : found;
    }
    return found;
  }

  /// The caller's entry from the `authorization` metadata, or the UNAUTHENTICATED status.
  grpc::Status Authenticate(const std::string_view* authorization, const Entry** entry) const {
    *entry = nullptr;
    if (authorization == nullptr) {
      return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                          "missing 'authorization: Bearer <token>' metadata: this server requires a bearer token");
    }
    const std::string_view value = Trim(*authorization);
    const std::size_t space = value.find(' ');
    if (space == std::string_view::npos || !EqualsIgnoreCase(value.substr(0, space), "Bearer")) {
      return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                          "the 'authorization' metadata must be 'Bearer <token>' (another scheme or no token was sent)");
    }
    *entry = Find(Trim(value.substr(space + 1)));
    if (*entry == nullptr) {
      return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                          "unknown token: the bearer token matches none of the server's --tokens");
    }
    return grpc::Status::OK;
  }

  /// The full check of one call of `rpc` (method name or gRPC path); `*entry` is the caller's
  /// entry when the token was known.
  grpc::Status Check(std::string_view rpc, const std::string_view* authorization, const Entry** entry) const {
    *entry = nullptr;
    const Permission needed = RequiredPermission(rpc);
    if (needed == Permission::kOpen) return grpc::Status::OK;
    grpc::Status status = Authenticate(authorization, entry);
    if (!status.ok()) return status;
    if (needed == Permission::kCommit && (*entry)->role != Permission::kCommit) {
      std::string method(rpc);
      if (method.rfind(kPlanningService, 0) == 0) method = method.substr(kPlanningService.size());
      return grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                          method + " needs a token with role 'commit'; the token of " + Quoted((*entry)->name) +
                              " has role '" + RoleName((*entry)->role) + "'");
    }
    return grpc::Status::OK;
  }

  std::size_t size() const { return entries_.size(); }
  std::size_t count(Permission role) const {
    return static_cast<std::size_t>(
        std::count_if(entries_.begin(), entries_.end(), [role](const Entry& e) { return e.role == role; }));
  }

 private:
  std::vector<Entry> entries_;
};

namespace {

/// Checks every call's token before any handler runs. It sees the ":path" pseudo-header (gRPC
/// 1.51 passes all of the call's initial metadata), so it knows the method and its permission.
/// It adds nothing to the AuthContext: that context is shared by all calls of a connection.
class TokenProcessor final : public grpc::AuthMetadataProcessor {
 public:
  TokenProcessor(std::shared_ptr<const TokenTable> tokens, std::function<void(const AccessRefusal&)> on_refusal)
      : tokens_(std::move(tokens)), on_refusal_(std::move(on_refusal)) {}

  bool IsBlocking() const override { return false; }  // a hash and a few comparisons

  grpc::Status Process(const InputMetadata& metadata, grpc::AuthContext*, OutputMetadata*, OutputMetadata*) override {
    std::string_view path;
    std::string_view authorization;
    bool has_authorization = false;
    for (const auto& [key, value] : metadata) {
      const std::string_view k(key.data(), key.size());
      if (k == ":path") path = std::string_view(value.data(), value.size());
      if (k == "authorization") {
        authorization = std::string_view(value.data(), value.size());
        has_authorization = true;
      }
    }
    const TokenTable::Entry* entry = nullptr;
    grpc::Status status = tokens_->Check(path, has_authorization ? &authorization : nullptr, &entry);
    if (!status.ok() && on_refusal_) {
      AccessRefusal refusal;
      refusal.rpc = std::string(path);
      refusal.code = status.error_code();
      refusal.message = status.error_message();
      if (entry != nullptr) refusal.name = entry->name;
      on_refusal_(refusal);
    }
    return status;
  }

 private:
  std::shared_ptr<const TokenTable> tokens_;
  std::function<void(const AccessRefusal&)> on_refusal_;
};

/// The call's `authorization` metadata, if sent.
bool FindAuthorization(const grpc::ServerContextBase& context, std::string_view* value) {
  const auto& metadata = context.client_metadata();
  const auto it = metadata.find("authorization");
  if (it == metadata.end()) return false;
  *value = std::string_view(it->second.data(), it->second.size());
  return true;
}

std::string FirstProperty(const grpc::AuthContext& context, const char* name) {
  const std::vector<grpc::string_ref> values = context.FindPropertyValues(name);
  return values.empty() ? std::string() : std::string(values.front().data(), values.front().size());
}

}  // namespace

void SecurityOptions::Validate() const {
  ValidateTls(*this);
  if (tokens()) TokenTable::Load(tokens_file);
}

Permission RequiredPermission(std::string_view rpc) {
  if (rpc.rfind("/grpc.health.v1.Health/", 0) == 0) return Permission::kOpen;
  if (rpc.rfind("/grpc.reflection.v1alpha.ServerReflection/", 0) == 0) return Permission::kOpen;
  if (rpc.rfind("/grpc.reflection.v1.ServerReflection/", 0) == 0) return Permission::kOpen;
  std::string_view method = rpc;
  if (method.rfind(kPlanningService, 0) == 0) method.remove_prefix(kPlanningService.size());
  static constexpr std::string_view kPlanMethods[] = {
      "Plan",        "Optimize",    "InverseKinematics", "CartesianPath", "ListPlanners", "UploadRobot",
      "UploadScene", "UpdateScene", "Coordinate",        "Benchmark",     "StopBenchmark", "Replan",
      "View"};  // View: the viewer pages over HTTP (--http-listen)
  for (std::string_view plan : kPlanMethods) {
    if (method == plan) return Permission::kPlan;
  }
  // CreateWorkcell, CommitTrajectory, Release change the shared workcell state others plan
  // against; anything unknown is denied to `plan` tokens too.
  return Permission::kCommit;
}

AccessControl::AccessControl(const SecurityOptions& options, std::function<void(const AccessRefusal&)> on_refusal)
    : options_(options), on_refusal_(std::move(on_refusal)) {
  ValidateTls(options_);
  if (options_.tokens()) tokens_ = TokenTable::Load(options_.tokens_file);
}

AccessControl::~AccessControl() = default;

bool AccessControl::tokens_enabled() const { return tokens_ != nullptr; }

std::size_t AccessControl::token_count() const { return tokens_ ? tokens_->size() : 0; }

std::shared_ptr<grpc::ServerCredentials> AccessControl::MakeServerCredentials() const {
  std::shared_ptr<grpc::ServerCredentials> credentials;
  if (options_.tls()) {
    grpc::SslServerCredentialsOptions ssl(options_.mutual_tls()
                                              ? GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY
                                              : GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
    if (options_.mutual_tls()) ssl.pem_root_certs = ReadFile("--tls-client-ca", options_.tls_client_ca);
    ssl.pem_key_cert_pairs.push_back({ReadFile("--tls-key", options_.tls_key), ReadFile("--tls-cert", options_.tls_cert)});
    credentials = grpc::SslServerCredentials(ssl);
  } else if (tokens_) {
    // InsecureServerCredentials cannot carry an AuthMetadataProcessor; local credentials can,
    // and admit loopback peers only: tokens never cross a network in plaintext.
    credentials = grpc::experimental::LocalServerCredentials(LOCAL_TCP);
  } else {
    return grpc::InsecureServerCredentials();
  }
  if (!credentials) throw std::runtime_error("gRPC refused to create the server credentials");
  if (tokens_) credentials->SetAuthMetadataProcessor(std::make_shared<TokenProcessor>(tokens_, on_refusal_));
  return credentials;
}

ClientIdentity AccessControl::IdentifyClient(const grpc::ServerContextBase& context) const {
  ClientIdentity identity;
  std::string_view authorization;
  if (tokens_ && FindAuthorization(context, &authorization)) {
    const TokenTable::Entry* entry = nullptr;
    if (tokens_->Authenticate(&authorization, &entry).ok()) {
      identity.name = entry->name;
      identity.role = RoleName(entry->role);
      identity.authenticated = true;
      return identity;
    }
  }
  const std::shared_ptr<const grpc::AuthContext> auth = context.auth_context();
  if (auth && auth->IsPeerAuthenticated()) {
    identity.name = FirstProperty(*auth, GRPC_X509_CN_PROPERTY_NAME);
    if (identity.name.empty()) {
      const std::vector<grpc::string_ref> peer = auth->GetPeerIdentity();
      if (!peer.empty()) identity.name.assign(peer.front().data(), peer.front().size());
    }
    if (!identity.name.empty()) {
      identity.authenticated = true;
      return identity;
    }
  }
  identity.name = context.peer();
  return identity;
}

grpc::Status AccessControl::Authorize(const grpc::ServerContextBase& context, std::string_view rpc) const {
  if (!tokens_) return grpc::Status::OK;
  std::string_view authorization;
  const bool sent = FindAuthorization(context, &authorization);
  const TokenTable::Entry* entry = nullptr;
  return tokens_->Check(rpc, sent ? &authorization : nullptr, &entry);
}

grpc::Status AccessControl::AuthorizeHeader(const std::optional<std::string>& authorization, std::string_view rpc) const {
  if (!tokens_) return grpc::Status::OK;
  const TokenTable::Entry* entry = nullptr;
  if (!authorization) return tokens_->Check(rpc, nullptr, &entry);
  const std::string_view value = *authorization;
  return tokens_->Check(rpc, &value, &entry);
}

std::string AccessControl::Describe() const {
  std::string text = options_.tls() ? (options_.mutual_tls() ? "TLS with client certificates (mutual TLS)" : "TLS")
                                    : "plaintext";
  if (tokens_) {
    text += ", " + std::to_string(tokens_->size()) + (tokens_->size() == 1 ? " bearer token (" : " bearer tokens (") + std::to_string(tokens_->count(Permission::kPlan)) +
            " plan, " + std::to_string(tokens_->count(Permission::kCommit)) + " commit)";
    if (!options_.tls()) text += " accepted from loopback peers only";
  } else {
    text += ", no tokens";
  }
  return text;
}

std::shared_ptr<grpc::ServerCredentials> MakeServerCredentials(const SecurityOptions& options) {
  return AccessControl(options).MakeServerCredentials();
}

bool IsLoopbackAddress(std::string_view listen) {
  std::string_view host = listen;
  if (!host.empty() && host.front() == '[') {
    const std::size_t end = host.find(']');
    host = end == std::string_view::npos ? host.substr(1) : host.substr(1, end - 1);
  } else if (const std::size_t colon = host.rfind(':'); colon != std::string_view::npos) {
    host = host.substr(0, colon);
  }
  if (host.rfind("ipv4:", 0) == 0) host.remove_prefix(5);
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

}  // namespace chasles
