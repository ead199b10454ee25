#include "chasles/server/request_log.h"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace chasles {
namespace {

/// Where `text` is cut for `max_bytes`, and the suffix saying how much was cut.
std::string_view Cut(std::string_view text, std::size_t max_bytes, std::string* suffix) {
  if (text.size() <= max_bytes) return text;
  *suffix = "…(+" + std::to_string(text.size() - max_bytes) + " bytes)";
  return text.substr(0, max_bytes);
}

std::string Milliseconds(double seconds) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.1f", 1e3 * seconds);
  return buffer;
}

/// A text value: escaped, and quoted when empty or when it holds a space, '=' or '"'.
std::string TextValue(std::string_view value, std::size_t max_bytes) {
  std::string escaped = EscapeForLog(value, max_bytes);
  if (!escaped.empty() && escaped.find_first_of(" =\"") == std::string::npos) return escaped;
  return "\"" + escaped + "\"";
}

std::string UtcNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1,
                tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(millis));
  return buffer;
}

}  // namespace

std::string EscapeForLog(std::string_view text, std::size_t max_bytes) {
  std::string suffix;
  const std::string_view kept = Cut(text, max_bytes, &suffix);
  std::string out;
  out.reserve(kept.size() + suffix.size());
  for (const char ch : kept) {
    const auto byte = static_cast<unsigned char>(ch);
    switch (ch) {
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      default:
        if (byte < 0x20 || byte >= 0x7f) {
          char hex[8];
          std::snprintf(hex, sizeof(hex), "\\x%02x", byte);
          out += hex;
        } else {
          out += ch;
        }
    }
  }
  return out + suffix;
}

std::string JsonString(std::string_view text, std::size_t max_bytes) {
  std::string suffix;
  const std::string_view kept = Cut(text, max_bytes, &suffix);
  std::string out = "\"";
  for (const char ch : kept) {
    const auto byte = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (byte < 0x20 || byte >= 0x7f) {
          char hex[8];
          std::snprintf(hex, sizeof(hex), "\\u%04x", byte);
          out += hex;
        } else {
          out += ch;
        }
    }
  }
  // The suffix is ASCII but for the ellipsis; write it as \u2026.
  if (!suffix.empty()) out += "\\u2026" + suffix.substr(std::string("…").size());
  return out + "\"";
}

const char* StatusCodeName(int code) {
  static const char* const kNames[] = {"OK",
                                       "CANCELLED",
                                       "UNKNOWN",
                                       "INVALID_ARGUMENT",
                                       "DEADLINE_EXCEEDED",
                                       "NOT_FOUND",
                                       "ALREADY_EXISTS",
                                       "PERMISSION_DENIED",
                                       "RESOURCE_EXHAUSTED",
                                       "FAILED_PRECONDITION",
                                       "ABORTED",
                                       "OUT_OF_RANGE",
                                       "UNIMPLEMENTED",
                                       "INTERNAL",
                                       "UNAVAILABLE",
                                       "DATA_LOSS",
                                       "UNAUTHENTICATED"};
  if (code < 0 || code >= static_cast<int>(sizeof(kNames) / sizeof(kNames[0]))) return "OTHER";
  return kNames[code];
}

std::string FormatLogLine(const RequestRecord& record, LogFormat format, std::size_t max_field_bytes) {
  const std::size_t cap = max_field_bytes;
  // Messages are ours but quote client text; they get a larger cap than single values.
  const std::size_t message_cap = 4 * max_field_bytes;
  if (format == LogFormat::kJson) {
    std::string line = "{\"time\":\"" + UtcNow() + "\",\"rpc\":" + JsonString(record.rpc, cap) +
                       ",\"request_id\":" + JsonString(record.request_id, cap) +
                       ",\"client\":" + JsonString(record.client, cap) + ",\"status\":\"" +
                       StatusCodeName(record.status_code) + "\",\"outcome\":" + JsonString(record.outcome, cap) +
                       ",\"message\":" + JsonString(record.status_message, message_cap) +
                       ",\"queue_ms\":" + Milliseconds(record.queue_seconds) +
                       ",\"total_ms\":" + Milliseconds(record.total_seconds) + ",\"stages_ms\":{";
    for (std::size_t k = 0; k < record.stages.size(); ++k) {
      if (k > 0) line += ",";
      line += JsonString(record.stages[k].first, cap) + ":" + Milliseconds(record.stages[k].second);
    }
    line += "},\"fields\":{";
    for (std::size_t k = 0; k < record.fields.size(); ++k) {
      if (k > 0) line += ",";
      line += JsonString(record.fields[k].first, cap) + ":" + JsonString(record.fields[k].second, cap);
    }
    line += "},\"peak_heap_bytes\":" + std::to_string(record.peak_heap_bytes) + "}";
    return line;
  }
  std::string line = "chasles-server: " + EscapeForLog(record.rpc, cap);
  line += " request=" + TextValue(record.request_id.empty() ? "-" : record.request_id, cap);
  line += " client=" + TextValue(record.client, cap);
  line += std::string(" status=") + StatusCodeName(record.status_code);
  line += " outcome=" + TextValue(record.outcome.empty() ? "-" : record.outcome, cap);
  for (const auto& [key, value] : record.fields) line += " " + EscapeForLog(key, cap) + "=" + TextValue(value, cap);
  line += " ms queue=" + Milliseconds(record.queue_seconds);
  for (const auto& [stage, seconds] : record.stages) line += " " + EscapeForLog(stage, cap) + "=" + Milliseconds(seconds);
  line += " total=" + Milliseconds(record.total_seconds);
  if (record.status_code != 0) line += " error=" + TextValue(record.status_message, message_cap);
  return line;
}

}  // namespace chasles
