#include "connection.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

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

/// Methods a client may send again on UNAVAILABLE: they change nothing, or nothing twice.
constexpr const char* kIdempotentMethods[] = {"Plan",           "ListPlanners",      "UploadRobot",
                                              "UploadScene",    "UpdateScene",       "InverseKinematics",
                                              "CartesianPath",  "Optimize",          "Coordinate",
                                              "CreateWorkcell"};

/// round_robin over the resolved addresses; the idempotent methods retried on UNAVAILABLE,
/// up to 5 attempts, backing off 0.1 s × 2^k up to 1 s (as the Python client).
std::string ServiceConfig() {
  std::string names;
  for (const char* method : kIdempotentMethods) {
    names += std::string(names.empty() ? "" : ",") + R"({"service":"chasles.v1.Planning","method":")" + method + "\"}";
  }
  return R"({"loadBalancingConfig":[{"round_robin":{}}],"methodConfig":[{"name":[)" + names +
         R"(],"retryPolicy":{"maxAttempts":5,"initialBackoff":"0.1s","maxBackoff":"1s","backoffMultiplier":2,)"
         R"("retryableStatusCodes":["UNAVAILABLE"]}}]})";
}

/// The channel target of --server: one address as given, or several (comma-separated) resolved
/// here into one static list (ipv4:a,b or ipv6:[a],[b]).
std::string Target(const std::string& server) {
  const std::vector<std::string> addresses = ServerAddresses(server);
  if (addresses.size() == 1) return addresses[0];
  std::vector<std::string> resolved;
  bool v4 = false, v6 = false;
  for (const std::string& address : addresses) {
    const std::size_t colon = address.rfind(':');
    if (colon == std::string::npos || colon == 0) ConnectionError("--server '" + address + "' must be HOST:PORT");
    std::string host = address.substr(0, colon);
    const std::string port = address.substr(colon + 1);
    if (host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    addrinfo hints{};
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    if (const int error = getaddrinfo(host.c_str(), port.c_str(), &hints, &found); error != 0) {
      ConnectionError("--server '" + address + "' does not resolve: " + gai_strerror(error));
    }
    for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
      char text[INET6_ADDRSTRLEN] = {0};
      std::string entry;
      if (a->ai_family == AF_INET) {
        inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ai_addr)->sin_addr, text, sizeof(text));
        entry = std::string(text) + ":" + port;
        v4 = true;
      } else if (a->ai_family == AF_INET6) {
        inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(a->ai_addr)->sin6_addr, text, sizeof(text));
        entry = "[" + std::string(text) + "]:" + port;
        v6 = true;
      }
      if (!entry.empty() && std::find(resolved.begin(), resolved.end(), entry) == resolved.end()) {
        resolved.push_back(entry);
      }
    }
    freeaddrinfo(found);
  }
  if (v4 && v6) ConnectionError("--server '" + server + "' mixes IPv4 and IPv6 addresses; give one family");
  std::string target = v6 ? "ipv6:" : "ipv4:";
  for (std::size_t i = 0; i < resolved.size(); ++i) target += (i > 0 ? "," : "") + resolved[i];
  return target;
}

}  // namespace

std::vector<std::string> ServerAddresses(const std::string& server) {
  std::vector<std::string> addresses;
  std::stringstream list(server);
  for (std::string item; std::getline(list, item, ',');) {
    item = Trim(item);
    if (!item.empty()) addresses.push_back(item);
  }
  if (addresses.empty()) ConnectionError("--server is empty: give HOST:PORT, or several separated by commas");
  return addresses;
}

const char kConnectionUsage[] =
    "  --server ADDR          server address, or several replicas separated by commas: calls are\n"
    "                         balanced round-robin and idempotent ones retried on UNAVAILABLE\n"
    "                         (default 127.0.0.1:50051)\n"
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
  channel_args.SetServiceConfigJSON(ServiceConfig());
  return grpc::CreateCustomChannel(Target(options.server), credentials, channel_args);
}

}  // namespace chasles::cli
