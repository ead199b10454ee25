#include "chasles/server/redis_client.h"

#include <hiredis.h>
#include <sys/time.h>

#include <cmath>
#include <utility>

#include "chasles/robot/error.h"
#include "chasles/server/status.h"

namespace chasles {
namespace {

/// `reply` when it holds no error reply (EXEC's results included); \throws Error(kUnavailable)
/// naming the command and what Redis said.
RedisReply Checked(RedisReply reply, const std::string& command, const std::string& address) {
  const auto fail = [&](const std::string& what) {
    throw Error(ErrorCode::kUnavailable, "the shared store Redis at " + address + " answered " + command +
                                             " with an error: " + what);
  };
  if (reply.type == RedisReply::Type::kError) fail(reply.str);
  for (const RedisReply& element : reply.elements) {
    if (element.type == RedisReply::Type::kError) fail(element.str);
  }
  return reply;
}

RedisReply Convert(const redisReply* r) {
  RedisReply out;
  if (r == nullptr) return out;
  switch (r->type) {
    case REDIS_REPLY_STRING: out.type = RedisReply::Type::kString; break;
    case REDIS_REPLY_STATUS: out.type = RedisReply::Type::kStatus; break;
    case REDIS_REPLY_ERROR: out.type = RedisReply::Type::kError; break;
    case REDIS_REPLY_INTEGER: out.type = RedisReply::Type::kInteger; break;
    case REDIS_REPLY_ARRAY: out.type = RedisReply::Type::kArray; break;
    default: out.type = RedisReply::Type::kNil; break;
  }
  if (r->type == REDIS_REPLY_STRING || r->type == REDIS_REPLY_STATUS || r->type == REDIS_REPLY_ERROR) {
    out.str.assign(r->str, r->len);
  }
  out.integer = r->integer;
  for (std::size_t i = 0; r->type == REDIS_REPLY_ARRAY && i < r->elements; ++i) {
    out.elements.push_back(Convert(r->element[i]));
  }
  return out;
}

int ParsePort(const std::string& text, const std::string& url, const std::string& field) {
  if (text.empty() || text.size() > 5 || text.find_first_not_of("0123456789") != std::string::npos) {
    ThrowInvalid(field + " = '" + url + "': the port must be a number in [1, 65535]");
  }
  const int port = std::stoi(text);
  if (port < 1 || port > 65535) ThrowInvalid(field + " = '" + url + "': the port must be a number in [1, 65535]");
  return port;
}

}  // namespace

std::string RedisAddress::text() const {
  return "redis://" + host + ":" + std::to_string(port) + "/" + std::to_string(db);
}

RedisAddress ParseRedisUrl(const std::string& url, const std::string& field) {
  const std::string scheme = "redis://";
  if (url.rfind(scheme, 0) != 0) ThrowInvalid(field + " = '" + url + "' must be memory or redis://HOST[:PORT][/DB]");
  std::string rest = url.substr(scheme.size());
  RedisAddress address;
  const std::size_t slash = rest.find('/');
  if (slash != std::string::npos) {
    const std::string db = rest.substr(slash + 1);
    if (db.empty() || db.size() > 2 || db.find_first_not_of("0123456789") != std::string::npos) {
      ThrowInvalid(field + " = '" + url + "': the database must be a number in [0, 15]");
    }
    address.db = std::stoi(db);
    if (address.db > 15) ThrowInvalid(field + " = '" + url + "': the database must be a number in [0, 15]");
    rest = rest.substr(0, slash);
  }
  const std::size_t colon = rest.rfind(':');
  if (colon != std::string::npos) {
    address.port = ParsePort(rest.substr(colon + 1), url, field);
    rest = rest.substr(0, colon);
  }
  if (rest.empty()) ThrowInvalid(field + " = '" + url + "' names no host");
  address.host = rest;
  return address;
}

RedisClient::RedisClient(RedisAddress address, double timeout_seconds)
    : address_(std::move(address)), timeout_seconds_(timeout_seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    Connect();
    Send({"PING"});  // an error reply (LOADING while it reads its append-only file) throws
  } catch (...) {
    // No destructor runs for a constructor that throws: free the connection here.
    if (context_ != nullptr) redisFree(context_);
    context_ = nullptr;
    throw;
  }
}

RedisClient::~RedisClient() {
  if (context_ != nullptr) redisFree(context_);
}

void RedisClient::Connect() {
  if (context_ != nullptr) {
    redisFree(context_);
    context_ = nullptr;
  }
  timeval tv;
  tv.tv_sec = static_cast<time_t>(timeout_seconds_);
  tv.tv_usec = static_cast<suseconds_t>((timeout_seconds_ - std::floor(timeout_seconds_)) * 1e6);
  redisContext* c = redisConnectWithTimeout(address_.host.c_str(), address_.port, tv);
  if (c == nullptr || c->err != 0) {
    const std::string why = c == nullptr ? "out of memory" : c->errstr;
    if (c != nullptr) redisFree(c);
    throw Error(ErrorCode::kUnavailable, "the shared store Redis at " + address_.text() + " cannot be reached: " + why);
  }
  redisSetTimeout(c, tv);
  context_ = c;
  if (address_.db != 0) Send({"SELECT", std::to_string(address_.db)});
}

RedisReply RedisClient::Send(const std::vector<std::string>& args) {
  if (context_ == nullptr) Connect();
  std::vector<const char*> argv;
  std::vector<std::size_t> lengths;
  for (const std::string& a : args) {
    argv.push_back(a.data());
    lengths.push_back(a.size());
  }
  auto* reply = static_cast<redisReply*>(
      redisCommandArgv(context_, static_cast<int>(args.size()), argv.data(), lengths.data()));
  if (reply == nullptr) {
    const std::string why = context_->errstr;
    redisFree(context_);
    context_ = nullptr;
    throw Error(ErrorCode::kUnavailable, "the shared store Redis at " + address_.text() + " failed: " + why);
  }
  RedisReply out = Convert(reply);
  freeReplyObject(reply);
  return Checked(std::move(out), args.empty() ? "" : args[0], address_.text());
}

std::vector<RedisReply> RedisClient::Pipeline(const std::vector<std::vector<std::string>>& commands) {
  if (context_ == nullptr) Connect();
  for (const std::vector<std::string>& args : commands) {
    std::vector<const char*> argv;
    std::vector<std::size_t> lengths;
    for (const std::string& a : args) {
      argv.push_back(a.data());
      lengths.push_back(a.size());
    }
    if (redisAppendCommandArgv(context_, static_cast<int>(args.size()), argv.data(), lengths.data()) != REDIS_OK) {
      throw Error(ErrorCode::kUnavailable, "the shared store Redis at " + address_.text() + " failed: " +
                                               std::string(context_->errstr));
    }
  }
  std::vector<RedisReply> replies;
  for (std::size_t k = 0; k < commands.size(); ++k) {
    void* raw = nullptr;
    if (redisGetReply(context_, &raw) != REDIS_OK || raw == nullptr) {
      const std::string why = context_->errstr;
      redisFree(context_);
      context_ = nullptr;
      throw Error(ErrorCode::kUnavailable, "the shared store Redis at " + address_.text() + " failed: " + why);
    }
    RedisReply reply = Convert(static_cast<redisReply*>(raw));
    freeReplyObject(raw);
    replies.push_back(std::move(reply));
  }
  for (std::size_t k = 0; k < commands.size(); ++k) {
    Checked(replies[k], commands[k].empty() ? "" : commands[k][0], address_.text());
  }
  return replies;
}

RedisReply RedisClient::Command(const std::vector<std::string>& args) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    return Send(args);
  } catch (const Error&) {
    if (context_ != nullptr) throw;  // an error reply: the connection is fine, the command is not
    return Send(args);               // once more on a fresh connection (Send dropped the broken one)
  }
}

void RedisClient::Transaction(const std::function<void(Held&)>& body) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (context_ == nullptr) Connect();
  try {
    Held held(*this);
    body(held);
  } catch (...) {
    // Leave no WATCH or MULTI behind on the connection.
    if (context_ != nullptr) {
      if (auto* reply = static_cast<redisReply*>(redisCommand(context_, "DISCARD"))) freeReplyObject(reply);
      if (auto* reply = static_cast<redisReply*>(redisCommand(context_, "UNWATCH"))) freeReplyObject(reply);
    }
    throw;
  }
}

}  // namespace chasles
