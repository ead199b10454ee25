#pragma once
/// \file
/// The request log: one line per finished call, as `key=value` text or as one JSON object.
/// Every value a client supplied is escaped (control characters, quotes, backslashes, bytes that
/// are not UTF-8 text) and cut to a length cap, so no request can forge, colour or flood a line.

#include <cstddef>
#include <string>
#include <string_view>

#include "chasles/server/request_record.h"

namespace chasles {

/// `text` with every byte outside printable ASCII, `"` and `\` written as an escape (`\n`, `\t`,
/// `\"`, `\\`, `\xHH`) and, when longer than `max_bytes`, cut there with "…(+N bytes)" appended.
std::string EscapeForLog(std::string_view text, std::size_t max_bytes);

/// A JSON string literal (quotes included) of `text`, escaped as RFC 8259 requires and every
/// byte >= 0x7f as `\u00HH` (the log stays ASCII), cut to `max_bytes` like EscapeForLog.
std::string JsonString(std::string_view text, std::size_t max_bytes);

enum class LogFormat { kText, kJson };

/// One line, without the trailing newline:
/// text: `chasles-server: <rpc> request=<id> client=<client> status=<code> outcome=<outcome>
///        <fields…> ms queue=<…> <stage>=<…> total=<…>[ error="<message>"]`, values escaped and
///        quoted when they contain spaces or '=';
/// JSON: `{"time":"2026-…Z","rpc":…,"request_id":…,"client":…,"status":…,"outcome":…,
///        "message":…,"queue_ms":…,"total_ms":…,"stages_ms":{…},"fields":{…},"peak_heap_bytes":…}`.
std::string FormatLogLine(const RequestRecord& record, LogFormat format, std::size_t max_field_bytes);

/// The gRPC status code's name ("OK", "INVALID_ARGUMENT", …).
const char* StatusCodeName(int code);

}  // namespace chasles
