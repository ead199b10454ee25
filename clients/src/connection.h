#pragma once
/// \file
/// How the chasles CLI reaches the server: address, TLS / mutual TLS and a bearer token.

#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

namespace chasles::cli {

/// The connection flags, shared by every command (bench included).
struct ConnectionOptions {
  std::string server = "127.0.0.1:50051";  ///< --server HOST:PORT
  std::string tls_ca;           ///< --tls-ca: CA (PEM) the server certificate must chain to; enables TLS
  std::string tls_cert;         ///< --tls-cert: client certificate (PEM) for mutual TLS; with --tls-key
  std::string tls_key;          ///< --tls-key: its private key (PEM)
  std::string tls_server_name;  ///< --tls-server-name: name to verify instead of the --server host
  std::string token;            ///< --token (else --token-file, else $CHASLES_TOKEN)
  std::string token_file;       ///< --token-file: a file holding the token (first line)
};

/// The usage lines of the connection flags.
extern const char kConnectionUsage[];

/// When argv[*i] is a connection flag, stores it with its value, advances *i past the value and
/// returns true; a flag without a value exits with status 2.
bool ParseConnectionFlag(int argc, char** argv, int* i, ConnectionOptions* options);

/// The addresses of --server: one, or several separated by commas (blanks trimmed). Exits with
/// status 2 and a message when none is given.
std::vector<std::string> ServerAddresses(const std::string& server);

/// The channel the flags describe: TLS when --tls-ca is set (mutual with --tls-cert/--tls-key),
/// plaintext otherwise; with a token every call carries `authorization: Bearer TOKEN` (over
/// plaintext through gRPC local credentials, loopback servers only). Exits with status 2 and a
/// message naming the flag and file when a file cannot be read or the flags do not fit together.
std::shared_ptr<grpc::Channel> MakeChannel(const ConnectionOptions& options, const grpc::ChannelArguments& args);

}  // namespace chasles::cli
