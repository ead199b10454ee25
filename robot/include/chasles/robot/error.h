#pragma once
/// \file
/// The one exception type the Chasles core throws for contract violations.

#include <stdexcept>
#include <string>

namespace chasles {

/// What kind of contract a caller broke. The server maps each to one gRPC status.
enum class ErrorCode {
  kInvalidArgument,     ///< malformed input: the message names field, index, value and rule
  kNotFound,            ///< an unknown planner, robot, scene or link id
  kFailedPrecondition,  ///< a capability that is not there for this input
  kResourceExhausted,   ///< an input within the rules but beyond a size cap of this server
                        ///< (the message names the field, the size, the cap and what to change)
  kUnavailable,         ///< a service the server depends on (the shared store) cannot be reached;
                        ///< retrying may succeed
};

/// `text` with bytes below 0x20 and 0x7f written as `\xHH` (other bytes, UTF-8 included, kept).
std::string EscapeControlCharacters(const std::string& text);

/// Thrown for contract violations (never for expected outcomes such as "no path").
/// `what()` is a complete human sentence, e.g.
/// `start.positions[2] = nan must be finite`.
class Error : public std::runtime_error {
 public:
  /// Control characters in `message` (a client's names may carry NUL, ESC, newlines) are written
  /// as `\xHH`, so what() — a C string — holds the whole message and prints safely.
  Error(ErrorCode code, const std::string& message)
      : std::runtime_error(EscapeControlCharacters(message)), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

/// Formats a number for messages: the shortest decimal text that reads back as exactly
/// `value` ("2", "0.0825", "-1", "nan", "-inf"). Every module's messages use it.
std::string FormatNumber(double value);

/// Throws Error(kInvalidArgument, message).
[[noreturn]] inline void ThrowInvalid(const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, message);
}

/// Throws Error(kResourceExhausted, message).
[[noreturn]] inline void ThrowResourceExhausted(const std::string& message) {
  throw Error(ErrorCode::kResourceExhausted, message);
}

}  // namespace chasles
