#pragma once
// Internal: a cheap, iterative pre-scan of XML text before it reaches tinyxml, whose parser
// recurses once per nested element (so deep nesting overflows the stack). The scan follows
// tinyxml 2.6's own reading rules (element tags and quoted attribute values, comments, CDATA,
// `<?xml ?>` declarations, other `<!`/`<?` constructs ending at the first `>`, UTF-8 lead bytes
// that swallow the next bytes in text and attribute values), so the depth it reports is the
// depth tinyxml would reach on the same text, in either of the encodings it may parse in.

#include <cstddef>
#include <string>
#include <string_view>

namespace chasles {
namespace robot_internal {

struct XmlScan {
  int max_depth = 0;            ///< deepest element nesting (the root element is depth 1)
  bool depth_exceeded = false;  ///< max_depth > the cap given to the scan
  std::size_t links = 0;        ///< <link> elements that are children of the root element
  std::size_t joints = 0;       ///< <joint> elements that are children of the root element
  std::size_t moving_joints = 0;  ///< of those, the ones whose type attribute is not "fixed"
};

/// Scans `text` in tinyxml's byte-wise reading (`utf8` false) or its UTF-8 reading (`utf8`
/// true); linear time, constant memory.
XmlScan ScanXml(std::string_view text, bool utf8, int depth_cap);

/// Checks `text` against the limits before any XML parser sees it: at most `max_bytes` bytes,
/// no NUL byte, no UTF-8 sequence cut by the end of the text (tinyxml would read past the end),
/// element nesting at most `max_depth` in either reading. Returns the larger scan's counts.
/// \throws Error(kResourceExhausted) for size and depth, Error(kInvalidArgument) for NUL bytes
///         and cut sequences; messages start with `field`.
XmlScan CheckXmlText(std::string_view text, const std::string& field, std::size_t max_bytes, int max_depth);

}  // namespace robot_internal
}  // namespace chasles
