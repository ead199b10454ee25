#pragma once
/// \file
/// A small synchronous Redis client on hiredis for the server's shared store (`--store
/// redis://HOST:PORT[/DB]`): one connection, commands as argument vectors (binary-safe), and
/// transactions that hold the connection for WATCH … MULTI … EXEC. Thread-safe (calls are
/// serialised on the connection). A lost connection is re-opened once per command; a server
/// that cannot be reached is Error(kUnavailable) naming the address.

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

struct redisContext;

namespace chasles {

/// A Redis reply, converted from hiredis's.
struct RedisReply {
  enum class Type { kNil, kString, kStatus, kInteger, kArray, kError };
  Type type = Type::kNil;
  std::string str;      ///< kString, kStatus, kError
  long long integer = 0;  ///< kInteger
  std::vector<RedisReply> elements;  ///< kArray
  bool nil() const { return type == Type::kNil; }
};

/// Where a `redis://HOST:PORT[/DB]` URL points.
struct RedisAddress {
  std::string host = "127.0.0.1";
  int port = 6379;
  int db = 0;
  std::string text() const;
};

/// \throws Error(kInvalidArgument) naming `field` for anything but redis://HOST[:PORT][/DB].
RedisAddress ParseRedisUrl(const std::string& url, const std::string& field = "--store");

class RedisClient {
 public:
  /// Connects (and SELECTs the database); \throws Error(kUnavailable) when Redis does not answer
  /// PING within `timeout_seconds`.
  explicit RedisClient(RedisAddress address, double timeout_seconds = 2.0);
  ~RedisClient();
  RedisClient(const RedisClient&) = delete;
  RedisClient& operator=(const RedisClient&) = delete;

  /// One command. \throws Error(kUnavailable) when the connection fails twice, or when Redis
  /// answers with an error reply (naming the command and Redis's message).
  RedisReply Command(const std::vector<std::string>& args);

  /// The connection while Transaction holds it: commands go to it with no other caller's in
  /// between (WATCH / MULTI / EXEC). No reconnect: a failure is Error(kUnavailable), as is an
  /// error reply.
  class Held {
   public:
    RedisReply Send(const std::vector<std::string>& args) { return client_.Send(args); }
    /// Several commands sent at once and their replies read in order: one round trip.
    std::vector<RedisReply> Pipeline(const std::vector<std::vector<std::string>>& commands) {
      return client_.Pipeline(commands);
    }

   private:
    friend class RedisClient;
    explicit Held(RedisClient& client) : client_(client) {}
    RedisClient& client_;
  };

  /// Runs `body` with the connection held (see Held); a WATCH or MULTI it leaves open when it
  /// throws is discarded.
  void Transaction(const std::function<void(Held&)>& body);

  const RedisAddress& address() const { return address_; }

 private:
  RedisReply Send(const std::vector<std::string>& args);  ///< mutex held
  std::vector<RedisReply> Pipeline(const std::vector<std::vector<std::string>>& commands);  ///< mutex held
  void Connect();                                         ///< mutex held

  RedisAddress address_;
  double timeout_seconds_;
  std::mutex mutex_;
  redisContext* context_ = nullptr;
};

}  // namespace chasles
