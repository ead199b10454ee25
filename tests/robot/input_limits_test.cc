// Hostile robot descriptions: InputLimits (size caps, refused with kResourceExhausted before any
// parser works on the text), the XML nesting pre-scan (tinyxml recurses per level), the
// iterative tree walk, and the mass/inertia rules. Each case is a regression test of a crash
// or a gap found by hand or by fuzzing (docs/fuzzing.md).

#include <string>

#include <gtest/gtest.h>

#include "chasles/robot/descriptions.h"
#include "chasles/robot/input_limits.h"
#include "chasles/robot/robot_model.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ExpectInvalid;
using testing::ReadExample;

void ExpectExhausted(const std::function<void()>& fn, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no Error thrown; expected: " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
    EXPECT_EQ(std::string(e.what()), message);
  }
}

std::string Urdf(const std::string& body) { return "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n" + body + "</robot>\n"; }

std::string Nested(int depth) {
  std::string text;
  for (int i = 0; i < depth; ++i) text += "<a>";
  for (int i = 0; i < depth; ++i) text += "</a>";
  return text;
}

/// A serial chain of `links` links joined by joints of `type`.
std::string Chain(int links, const std::string& type) {
  std::string body;
  for (int i = 0; i < links; ++i) body += "<link name=\"l" + std::to_string(i) + "\"/>\n";
  for (int i = 1; i < links; ++i) {
    body += "<joint name=\"j" + std::to_string(i) + "\" type=\"" + type + "\"><parent link=\"l" +
            std::to_string(i - 1) + "\"/><child link=\"l" + std::to_string(i) + "\"/>" +
            (type == "fixed" ? "" : "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/>") +
            "</joint>\n";
  }
  return Urdf(body);
}

TEST(InputLimitsTest, DefaultsAreValidAndValidateNamesABadField) {
  EXPECT_NO_THROW(InputLimits{}.Validate());
  InputLimits limits;
  limits.max_xml_depth = 0;
  ExpectInvalid([&] { limits.Validate(); }, "input_limits.max_xml_depth = 0 must be > 0");
  limits = InputLimits{};
  limits.max_cloud_points = 0;
  ExpectInvalid([&] { limits.Validate(); }, "input_limits.max_cloud_points = 0 must be > 0");
}

// 10^5 nested elements (about 700 KB) overflowed the stack in tinyxml's recursive parser.
TEST(InputLimitsTest, DeeplyNestedUrdfIsRefusedBeforeTinyxmlSeesIt) {
  const std::string urdf = "<robot name=\"r\">" + Nested(100000) + "</robot>";
  ASSERT_GT(urdf.size(), 700000u);
  ExpectExhausted([&] { RobotModel::FromUrdf(urdf); },
                  "urdf nests XML elements 100001 deep, more than the cap of 64 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
  const std::string srdf = "<robot name=\"r\">" + Nested(5000) + "</robot>";
  ExpectExhausted([&] { RobotModel::FromUrdf(ReadExample("robots/planar_2r.urdf"), srdf); },
                  "srdf nests XML elements 5001 deep, more than the cap of 64 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
}

TEST(InputLimitsTest, NestingCapCountsElementsTheWayTinyxmlReadsThem) {
  InputLimits limits;
  limits.max_xml_depth = 3;  // robot > link > a
  const std::string ok_body = "<link name=\"base\"><a/></link>";
  EXPECT_NO_THROW(RobotModel::FromUrdf(Urdf(ok_body), {}, {}, limits));
  // What is not an element does not nest: comments, CDATA, processing instructions, DOCTYPE,
  // '>' inside quoted attribute values, self-closing tags.
  const std::string hidden = "<link name=\"base\"><!-- <a><a><a> --><![CDATA[<a><a>]]><?pi <a>?>"
                             "<a title=\"x>y\" other='<b>'/></link>";
  EXPECT_NO_THROW(RobotModel::FromUrdf("<!DOCTYPE robot>" + Urdf(hidden), {}, {}, limits));
  ExpectExhausted([&] { RobotModel::FromUrdf(Urdf("<link name=\"base\"><a><b/></a></link>"), {}, {}, limits); },
                  "urdf nests XML elements 4 deep, more than the cap of 3 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
  // tinyxml keeps an element whose tag never ends at its depth (found by fuzz_urdf's check of
  // the pre-scan against tinyxml's tree).
  ExpectExhausted([&] { RobotModel::FromUrdf("<robot name=\"r\"><link name=\"base\"><a><b", {}, {}, limits); },
                  "urdf nests XML elements 4 deep, more than the cap of 3 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
  // tinyxml reads a UTF-8 lead byte with the bytes after it, so "\xE0</a>" is text to it, not an
  // end tag: the nesting goes on. The pre-scan reads it the same way.
  std::string lead_bytes = "<robot name=\"r\">";
  for (int i = 0; i < 10; ++i) lead_bytes += "<a>\xE0</a>";
  ExpectExhausted([&] { RobotModel::FromUrdf(lead_bytes + "</robot>", {}, {}, limits); },
                  "urdf nests XML elements 11 deep, more than the cap of 3 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
}

TEST(InputLimitsTest, BytesTinyxmlWouldReadPastAreRefused) {
  ExpectInvalid([&] { RobotModel::FromUrdf(std::string("<robot name=\"r\">") + '\0' + "</robot>"); },
                "urdf holds a NUL byte at offset 16; XML text cannot contain NUL");
  // tinyxml would copy the 4-byte sequence the last byte starts, reading past the text's end.
  const std::string cut = Urdf("<link name=\"base\"/>") + "\xF0";
  ExpectInvalid([&] { RobotModel::FromUrdf(cut); },
                "urdf ends inside a UTF-8 sequence (byte " + std::to_string(cut.size() - 1) +
                    " starts a 4-byte sequence); the text must be complete UTF-8");
}

TEST(InputLimitsTest, DocumentBytesAreCapped) {
  InputLimits limits;
  limits.max_document_bytes = 100;
  const std::string urdf = Urdf("<link name=\"base\"/>" + std::string(200, ' '));
  ExpectExhausted([&] { RobotModel::FromUrdf(urdf, {}, {}, limits); },
                  "urdf holds " + std::to_string(urdf.size()) +
                      " bytes, more than the cap of 100 bytes per document (InputLimits::max_document_bytes); "
                      "send a smaller document or raise the server's cap");
}

// A chain of 10^4 fixed joints overflowed the stack of the recursive tree walk (ASan build).
TEST(InputLimitsTest, LongChainLoadsIterativelyInDepthFirstOrder) {
  const auto robot = RobotModel::FromUrdf(Chain(10000, "fixed"));
  ASSERT_EQ(robot->num_links(), 10000);
  EXPECT_EQ(robot->num_dofs(), 0);
  for (int i = 0; i < robot->num_links(); ++i) ASSERT_EQ(robot->links()[i].name, "l" + std::to_string(i));
}

TEST(InputLimitsTest, LinksJointsAndDofsAreCountedBeforeParsing) {
  ExpectExhausted([&] { RobotModel::FromUrdf(Chain(10001, "fixed")); },
                  "urdf declares 10001 links, more than the cap of 10000 (InputLimits::max_links); "
                  "send a smaller robot or raise the server's cap");
  InputLimits limits;
  limits.max_links = 20;
  std::string joints;
  for (int i = 0; i < 21; ++i) joints += "<joint name=\"j" + std::to_string(i) + "\" type=\"fixed\"/>";
  ExpectExhausted([&] { RobotModel::FromUrdf(Urdf("<link name=\"l0\"/>" + joints), {}, {}, limits); },
                  "urdf declares 21 joints, more than the cap of 20 (InputLimits::max_links bounds joints too); "
                  "send a smaller robot or raise the server's cap");
  ExpectExhausted([&] { RobotModel::FromUrdf(Chain(514, "revolute")); },
                  "urdf declares 513 joints that are not fixed, more than the cap of 512 degrees of freedom "
                  "(InputLimits::max_dofs); send a smaller robot or raise the server's cap");
  EXPECT_EQ(RobotModel::FromUrdf(Chain(513, "revolute"))->num_dofs(), 512);
}

// urdfdom joins links with owning pointers before it checks the tree: these leaked the parsed
// model (found by fuzz_urdf under LeakSanitizer).
TEST(InputLimitsTest, JointCyclesAreRefusedBeforeUrdfdomBuildsThem) {
  const auto joint = [](const std::string& name, const std::string& parent, const std::string& child) {
    return "<joint name=\"" + name + "\" type=\"fixed\"><parent link=\"" + parent + "\"/><child link=\"" + child +
           "\"/></joint>";
  };
  const std::string links = "<link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>";
  ExpectInvalid([&] { RobotModel::FromUrdf(Urdf(links + joint("j", "b", "b"))); },
                "urdf: joint 'j' parent = child = 'b'; a joint joins two different links");
  ExpectInvalid([&] { RobotModel::FromUrdf(Urdf(links + joint("j1", "b", "c") + joint("j2", "c", "b"))); },
                "urdf: joint 'j1' closes a cycle of joints through link 'c'; the links must form a tree");
  ExpectInvalid([&] { RobotModel::FromUrdf(Urdf(links + joint("j1", "a", "c") + joint("j2", "b", "c"))); },
                "urdf: joint 'j2' child = 'c' is already the child of joint 'j1'; a link has at most one parent joint");
}

TEST(InputLimitsTest, MassAndInertiaMustBePhysical) {
  const auto link = [](const std::string& mass, const std::string& inertia) {
    return Urdf("<link name=\"panda_link3\"><inertial><mass value=\"" + mass + "\"/><inertia " + inertia +
                "/></inertial></link>");
  };
  const std::string unit = "ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"";
  EXPECT_NO_THROW(RobotModel::FromUrdf(link("1", unit)));
  // urdfdom logged these and loaded the link with mass 0 / inertia 0.
  ExpectInvalid([&] { RobotModel::FromUrdf(link("nan", unit)); },
                "urdf: link 'panda_link3' inertial mass = nan must be >= 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(link("1e400", unit)); },
                "urdf: link 'panda_link3' inertial mass = inf must be >= 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(link("1", "ixx=\"1\" iyy=\"-inf\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"")); },
                "urdf: link 'panda_link3' inertial inertia iyy = -inf must be finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(link("-1", unit)); },
                "urdf: link 'panda_link3' inertial mass = -1 must be >= 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(link("1", "ixx=\"1\" iyy=\"-2\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"")); },
                "urdf: link 'panda_link3' inertial inertia = (ixx 1, iyy -2, izz 1, ixy 0, ixz 0, iyz 0) has principal "
                "moment -2; principal moments must be >= 0 (a rotational inertia is positive semidefinite)");
  // Positive diagonal, but an off-diagonal term that makes the matrix indefinite.
  ExpectInvalid([&] { RobotModel::FromUrdf(link("1", "ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"3\" ixz=\"0\" iyz=\"0\"")); },
                "urdf: link 'panda_link3' inertial inertia = (ixx 1, iyy 1, izz 1, ixy 3, ixz 0, iyz 0) has principal "
                "moment -2; principal moments must be >= 0 (a rotational inertia is positive semidefinite)");
}

TEST(InputLimitsTest, DescriptionsCapJointsAndCheckInertia) {
  DhDescription dh;
  DhJoint joint;
  joint.limits.lower = -1;
  joint.limits.upper = 1;
  joint.limits.velocity = 1;
  dh.joints.assign(513, joint);
  ExpectExhausted([&] { RobotFromDh(dh); },
                  "dh.joints has 513 joints, more than the cap of 512 degrees of freedom (InputLimits::max_dofs); "
                  "send a smaller robot or raise the server's cap");
  InputLimits limits;
  limits.max_links = 10;
  dh.joints.resize(9);
  ExpectExhausted([&] { RobotFromDh(dh, limits); },
                  "dh.joints has 9 joints, so 11 links, more than the cap of 10 (InputLimits::max_links); "
                  "send a smaller robot or raise the server's cap");
  dh.joints.resize(2);
  Inertial in;
  in.mass = 1.0;
  in.inertia = Eigen::Vector3d(1.0, -0.5, 1.0).asDiagonal();
  dh.joints[1].link.inertial = in;
  ExpectInvalid([&] { RobotFromDh(dh); },
                "dh.joints[1].link.inertial inertia = (ixx 1, iyy -0.5, izz 1, ixy 0, ixz 0, iyz 0) has principal "
                "moment -0.5; principal moments must be >= 0 (a rotational inertia is positive semidefinite)");
  PoeDescription poe;
  PoeJoint pj;
  pj.screw << 0, 0, 1, 0, 0, 0;
  pj.limits = joint.limits;
  poe.joints.assign(600, pj);
  ExpectExhausted([&] { RobotFromPoe(poe); },
                  "poe.joints has 600 joints, more than the cap of 512 degrees of freedom (InputLimits::max_dofs); "
                  "send a smaller robot or raise the server's cap");
}

TEST(InputLimitsTest, ExampleRobotsPassTheDefaults) {
  for (const std::string name : {"panda", "ur5", "planar_2r"}) {
    SCOPED_TRACE(name);
    EXPECT_NO_THROW(testing::LoadExampleRobot(name));
  }
}

}  // namespace
}  // namespace chasles
