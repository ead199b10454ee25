#include "xml_scan.h"

#include <algorithm>

#include "chasles/robot/error.h"

namespace chasles {
namespace robot_internal {
namespace {

// How tinyxml reads the text: byte by byte (legacy or undetermined encoding), as UTF-8 (a lead
// byte swallows its whole sequence in text and attribute values), or undetermined until a
// top-level <?xml ?> declaration and UTF-8 after it (what tinyxml does when the caller passes
// no encoding, as urdfdom does).
enum class Reading { kBytes, kUtf8, kUtf8AfterDeclaration };

bool IsSpace(unsigned char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}
// tinyxml's IsAlpha / IsAlphaNum: ASCII letters (digits), and every byte >= 127.
bool IsAlpha(unsigned char c) { return c >= 127 || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool IsNameChar(unsigned char c) {
  return IsAlpha(c) || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.' || c == ':';
}
// tinyxml's utf8ByteTable: bytes a UTF-8 lead byte claims (1 for anything else).
int Utf8Length(unsigned char c) {
  if (c >= 0xc2 && c <= 0xdf) return 2;
  if (c >= 0xe0 && c <= 0xef) return 3;
  if (c >= 0xf0 && c <= 0xf4) return 4;
  return 1;
}

class Scanner {
 public:
  Scanner(std::string_view text, Reading reading, int cap) : s_(text), reading_(reading), cap_(cap) {
    utf8_ = reading == Reading::kUtf8;
    // A UTF-8 byte-order mark switches an undetermined reading to UTF-8.
    if (reading == Reading::kUtf8AfterDeclaration && StartsWith(0, "\xef\xbb\xbf")) utf8_ = true;
  }

  XmlScan Run() {
    std::size_t i = 0;
    while (i < s_.size()) {
      if (At(i) != '<') {
        i = SkipText(i);
        continue;
      }
      if (depth_ > 0 && At(i + 1) == '/') {
        i = Find(i + 2, ">");  // tinyxml checks the name; a wrong one ends its parse anyway
        --depth_;
      } else if (StartsWithNoCase(i, "<?xml")) {
        i = SkipDeclaration(i + 5);
        if (depth_ == 0 && reading_ == Reading::kUtf8AfterDeclaration) utf8_ = true;
      } else if (StartsWith(i, "<!--")) {
        i = Find(i + 4, "-->");
      } else if (StartsWith(i, "<![CDATA[")) {
        i = Find(i + 9, "]]>");
      } else if (IsAlpha(At(i + 1)) || At(i + 1) == '_') {
        i = StartTag(i + 1);
      } else {
        i = Find(i + 1, ">");  // <!DOCTYPE …>, <?pi …>, anything else: up to the first '>'
      }
    }
    return result_;
  }

 private:
  unsigned char At(std::size_t i) const { return i < s_.size() ? static_cast<unsigned char>(s_[i]) : 0; }
  bool StartsWith(std::size_t i, std::string_view prefix) const { return s_.substr(std::min(i, s_.size())).substr(0, prefix.size()) == prefix; }
  bool StartsWithNoCase(std::size_t i, std::string_view prefix) const {
    if (i + prefix.size() > s_.size()) return false;
    for (std::size_t k = 0; k < prefix.size(); ++k) {
      unsigned char c = At(i + k);
      if (c >= 'A' && c <= 'Z') c = static_cast<unsigned char>(c - 'A' + 'a');
      if (c != static_cast<unsigned char>(prefix[k])) return false;
    }
    return true;
  }
  // Index just past the next `token` at or after `i` (the end of the text if there is none).
  std::size_t Find(std::size_t i, std::string_view token) const {
    const std::size_t at = s_.find(token, std::min(i, s_.size()));
    return at == std::string_view::npos ? s_.size() : at + token.size();
  }
  // One character of text or attribute value: a whole UTF-8 sequence when reading UTF-8.
  std::size_t Step(std::size_t i) const { return i + (utf8_ ? Utf8Length(At(i)) : 1); }
  std::size_t SkipSpace(std::size_t i) const {
    while (i < s_.size()) {
      if (utf8_ && (StartsWith(i, "\xef\xbb\xbf") || StartsWith(i, "\xef\xbf\xbe") || StartsWith(i, "\xef\xbf\xbf"))) {
        i += 3;
      } else if (IsSpace(At(i))) {
        ++i;
      } else {
        break;
      }
    }
    return i;
  }
  std::size_t SkipName(std::size_t i) const {
    if (!(IsAlpha(At(i)) || At(i) == '_')) return i;
    while (i < s_.size() && IsNameChar(At(i))) ++i;
    return i;
  }
  // Text up to the next '<' (element content; top-level text ends tinyxml's parse anyway).
  std::size_t SkipText(std::size_t i) const {
    while (i < s_.size() && At(i) != '<') i = Step(i);
    return i;
  }
  // A quoted value starting at its opening quote; returns the index past the closing quote.
  std::size_t SkipQuoted(std::size_t i) const {
    const unsigned char quote = At(i);
    ++i;
    while (i < s_.size() && At(i) != quote) i = Step(i);
    return std::min(i + 1, s_.size());
  }
  // name = value, from the name on; returns where tinyxml continues (its errors end its parse,
  // so after one we only need to keep going somewhere).
  std::size_t Attribute(std::size_t i, std::string_view* name, std::string_view* value) const {
    const std::size_t name_end = SkipName(i);
    if (name_end == i) return i + 1;
    *name = s_.substr(i, name_end - i);
    i = SkipSpace(name_end);
    if (At(i) != '=') return i;
    i = SkipSpace(i + 1);
    if (At(i) == '"' || At(i) == '\'') {
      const std::size_t end = SkipQuoted(i);
      *value = s_.substr(i + 1, end > i + 1 ? end - i - 2 : 0);
      return end;
    }
    const std::size_t start = i;
    while (i < s_.size() && !IsSpace(At(i)) && At(i) != '/' && At(i) != '>') {
      if (At(i) == '"' || At(i) == '\'') return i + 1;  // tinyxml: error
      ++i;
    }
    *value = s_.substr(start, i - start);
    return i;
  }
  // <?xml … ?>: ends at the first '>' outside the quoted version/encoding/standalone values.
  std::size_t SkipDeclaration(std::size_t i) const {
    while (i < s_.size()) {
      if (At(i) == '>') return i + 1;
      i = SkipSpace(i);
      if (StartsWithNoCase(i, "version") || StartsWithNoCase(i, "encoding") || StartsWithNoCase(i, "standalone")) {
        std::string_view name, value;
        i = Attribute(i, &name, &value);
      } else {
        while (i < s_.size() && At(i) != '>' && !IsSpace(At(i))) ++i;
      }
    }
    return i;
  }
  // An element from its name on: attributes, then '/>' or '>' (one level deeper).
  std::size_t StartTag(std::size_t i) {
    const std::size_t name_end = SkipName(i);
    const std::string_view name = s_.substr(i, name_end - i);
    std::string_view type;
    Reach(depth_ + 1);  // tinyxml keeps an element whose tag never ends, at this depth
    i = name_end;
    while (i < s_.size()) {
      i = SkipSpace(i);
      if (At(i) == '/') {
        if (At(i + 1) == '>') {  // <name/>: an element one level down, with nothing inside
          Count(name, type, depth_ + 1);
          return i + 2;
        }
        return i + 1;  // tinyxml: error
      }
      if (At(i) == '>') {
        ++depth_;
        Count(name, type, depth_);
        return i + 1;
      }
      std::string_view attribute, value;
      i = Attribute(i, &attribute, &value);
      if (attribute == "type") type = value;
    }
    return i;
  }
  // An element starts at `depth`.
  void Reach(int depth) {
    result_.max_depth = std::max(result_.max_depth, depth);
    if (depth > cap_) result_.depth_exceeded = true;
  }
  // A complete start tag at `depth`: a link or joint of the root element?
  void Count(std::string_view name, std::string_view type, int depth) {
    if (depth != 2) return;
    if (name == "link") ++result_.links;
    if (name == "joint") {
      ++result_.joints;
      if (type != "fixed") ++result_.moving_joints;
    }
  }

  std::string_view s_;
  Reading reading_;
  int cap_;
  bool utf8_ = false;
  int depth_ = 0;
  XmlScan result_;
};

}  // namespace

XmlScan ScanXml(std::string_view text, bool utf8, int depth_cap) {
  return Scanner(text, utf8 ? Reading::kUtf8 : Reading::kBytes, depth_cap).Run();
}

XmlScan CheckXmlText(std::string_view text, const std::string& field, std::size_t max_bytes, int max_depth) {
  if (text.size() > max_bytes) {
    ThrowResourceExhausted(field + " holds " + std::to_string(text.size()) + " bytes, more than the cap of " +
                           std::to_string(max_bytes) + " bytes per document (InputLimits::max_document_bytes); " +
                           "send a smaller document or raise the server's cap");
  }
  const std::size_t nul = text.find('\0');
  if (nul != std::string_view::npos) {
    ThrowInvalid(field + " holds a NUL byte at offset " + std::to_string(nul) + "; XML text cannot contain NUL");
  }
  // tinyxml reads a UTF-8 lead byte's whole sequence at once, even past the end of the text.
  const std::size_t tail = text.size() >= 3 ? text.size() - 3 : 0;
  for (std::size_t i = tail; i < text.size(); ++i) {
    const int length = Utf8Length(static_cast<unsigned char>(text[i]));
    if (i + length > text.size()) {
      ThrowInvalid(field + " ends inside a UTF-8 sequence (byte " + std::to_string(i) + " starts a " +
                   std::to_string(length) + "-byte sequence); the text must be complete UTF-8");
    }
  }
  XmlScan worst;
  for (Reading reading : {Reading::kBytes, Reading::kUtf8, Reading::kUtf8AfterDeclaration}) {
    const XmlScan scan = Scanner(text, reading, max_depth).Run();
    if (scan.depth_exceeded) {
      ThrowResourceExhausted(field + " nests XML elements " + std::to_string(scan.max_depth) +
                             " deep, more than the cap of " + std::to_string(max_depth) +
                             " (InputLimits::max_xml_depth); flatten the document or raise the server's cap");
    }
    if (scan.max_depth >= worst.max_depth) worst.max_depth = scan.max_depth;
    worst.links = std::max(worst.links, scan.links);
    worst.joints = std::max(worst.joints, scan.joints);
    worst.moving_joints = std::max(worst.moving_joints, scan.moving_joints);
  }
  return worst;
}

}  // namespace robot_internal
}  // namespace chasles
