#include "connection.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

namespace chasles::cli {
namespace {

[[noreturn]] void ConnectionError(const std::string& message) {
  std::cerr << "chasles: " << message << "\n(see chasles --help)\n";
  std::exit(2);
}

std::string ReadFlagFile(const char* flag, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ConnectionError(std::string(flag) + " '" + path + "' cannot be read: " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string Trim(std::string text) {
  const char* blanks = " \t\r\n";
  text.erase(0, text.find_first_not_of(blanks));
  const std::size_t end = text.find_last_not_of(blanks);
  text.erase(end == std::string::npos ? 0 : end + 1);
  return text;
}

/// The token from --token, --token-file or $CHASLES_TOKEN (first found), or "".
std::string Token(const ConnectionOptions& options) {
  if (!options.token.empty()) return options.token;
  if (!options.token_file.empty()) {
    std::istringstream lines(ReadFlagFile("--token-file", options.token_file));
    std::string first;
    std::getline(lines, first);
    first = Trim(first);
    if (first.empty()) ConnectionError("--token-file '" + options.token_file + "' holds no token on its first line");
    return first;
  }
  const char* env = std::getenv("CHASLES_TOKEN");
  return env != nullptr ? Trim(env) : std::string();
}

}  // namespace

const char kConnectionUsage[] =
    "  --server ADDR          server address (default 127.0.0.1:50051)\n"
    "  --tls-ca FILE          use TLS; trust server certificates signed by this CA (PEM)\n"
    "  --tls-cert FILE        client certificate (PEM) for mutual TLS; with --tls-key FILE\n"
    "  --tls-key FILE         the client certificate's private key (PEM)\n"
    "  --tls-server-name N    verify the server certificate for name N (default: the ADDR host)\n"
    "  --token TOKEN          bearer token (else --token-file FILE, else $CHASLES_TOKEN); without\n"
    "                         TLS it is sent only to loopback servers (gRPC local credentials)\n"
    "  --token-file FILE      read the bearer token from the first line of FILE\n";

bool ParseConnectionFlag(int argc, char** argv, int* i, ConnectionOptions* options) {
  const std::string flag = argv[*i];
  std::string* target = flag == "--server"            ? &options->server
                        : flag == "--tls-ca"          ? &options->tls_ca
                        : flag == "--tls-cert"        ? &options->tls_cert
                        : flag == "--tls-key"         ? &options->tls_key
                        : flag == "--tls-server-name" ? &options->tls_server_name
                        : flag == "--token"           ? &options->token
                        : flag == "--token-file"      ? &options->token_file
                                                      : nullptr;
  if (target == nullptr) return false;
  if (*i + 1 >= argc) ConnectionError(flag + " needs a value");
  *target = argv[++*i];
  return true;
}

std::shared_ptr<grpc::Channel> MakeChannel(const ConnectionOptions& options, const grpc::ChannelArguments& args) {
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    ConnectionError(options.tls_cert.empty() ? "--tls-key is set but --tls-cert is not: mutual TLS needs both"
                                             : "--tls-cert is set but --tls-key is not: mutual TLS needs both");
  }
  if (!options.tls_cert.empty() && options.tls_ca.empty()) {
    ConnectionError("--tls-cert needs --tls-ca: a client certificate is only sent over TLS");
  }
  if (!options.tls_server_name.empty() && options.tls_ca.empty()) {
    ConnectionError("--tls-server-name needs --tls-ca (TLS)");
  }
  const std::string token = Token(options);
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  grpc::ChannelArguments channel_args = args;
  if (!options.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadFlagFile("--tls-ca", options.tls_ca);
    if (!options.tls_cert.empty()) {
      ssl.pem_cert_chain = ReadFlagFile("--tls-cert", options.tls_cert);
      ssl.pem_private_key = ReadFlagFile("--tls-key", options.tls_key);
    }
    credentials = grpc::SslCredentials(ssl);
    if (!options.tls_server_name.empty()) channel_args.SetSslTargetNameOverride(options.tls_server_name);
  } else if (!token.empty()) {
    // Call credentials need a secure channel; local credentials are one, for loopback servers.
    credentials = grpc::experimental::LocalCredentials(LOCAL_TCP);
  } else {
    credentials = grpc::InsecureChannelCredentials();
  }
  if (!token.empty()) {
    credentials = grpc::CompositeChannelCredentials(credentials, grpc::AccessTokenCredentials(token));
  }
  return grpc::CreateCustomChannel(options.server, credentials, channel_args);
}

}  // namespace chasles::cli
