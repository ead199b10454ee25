// URDF + SRDF text -> RobotModel::FromUrdf. Input: the URDF, then optionally the separator
// "\n--SRDF--\n" and the SRDF. Also checks the XML pre-scan against tinyxml itself: whenever the
// pre-scan lets a text through, the element tree tinyxml builds from it (in either encoding it
// may read it with) is no deeper than the depth the pre-scan reported.

#include <cstdlib>
#include <utility>
#include <vector>

#include <tinyxml.h>

#include "chasles/robot/robot_model.h"
#include "fuzz_util.h"
#include "xml_scan.h"

namespace {

int TreeDepth(const TiXmlNode* root) {
  int deepest = 0;
  std::vector<std::pair<const TiXmlNode*, int>> stack{{root, 0}};
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    deepest = std::max(deepest, depth);
    for (const TiXmlNode* c = node->FirstChild(); c != nullptr; c = c->NextSibling()) {
      stack.emplace_back(c, c->ToElement() != nullptr ? depth + 1 : depth);
    }
  }
  return deepest;
}

void CheckScanAgainstTinyxml(const std::string& text) {
  chasles::robot_internal::XmlScan scan;
  try {
    scan = chasles::robot_internal::CheckXmlText(text, "xml", chasles::InputLimits{}.max_document_bytes,
                                                 chasles::InputLimits{}.max_xml_depth);
  } catch (const chasles::Error&) {
    return;
  }
  for (TiXmlEncoding encoding : {TIXML_ENCODING_UTF8, TIXML_ENCODING_UNKNOWN}) {
    TiXmlDocument doc;
    doc.Parse(text.c_str(), nullptr, encoding);
    const int depth = TreeDepth(&doc);
    if (depth > scan.max_depth) {
      std::fprintf(stderr, "tinyxml (encoding %d) built depth %d, the pre-scan said %d\n", static_cast<int>(encoding),
                   depth, scan.max_depth);
      std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const auto [urdf, srdf] = chasles::fuzz::Split(input, "\n--SRDF--\n");
  CheckScanAgainstTinyxml(std::string(urdf));
  chasles::fuzz::Expect([&, urdf = urdf, srdf = srdf] {
    const auto model = chasles::RobotModel::FromUrdf(urdf, srdf);
    std::vector<Eigen::Isometry3d> poses;
    model->ForwardKinematics(Eigen::VectorXd::Zero(model->num_dofs()), &poses);
  });
  return 0;
}
