#include "chasles/robot/attached_objects.h"

#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"

namespace chasles {

std::shared_ptr<const RobotModel> AttachObjects(const RobotModel& robot, const std::vector<AttachedObject>& objects,
                                                const std::string& field) {
  std::vector<Link> links = robot.links();
  std::vector<Joint> joints = robot.joints();
  std::vector<std::pair<std::string, std::string>> allowed;
  for (int a = 0; a < robot.num_links(); ++a) {
    for (int b = a + 1; b < robot.num_links(); ++b) {
      if (robot.allowed_collisions().IsAllowed(a, b)) allowed.emplace_back(links[a].name, links[b].name);
    }
  }
  const auto link_names = [&] {
    std::string names;
    for (const Link& l : robot.links()) names += (names.empty() ? "'" : ", '") + l.name + "'";
    return names;
  };
  std::set<std::string> taken;
  for (const Link& l : links) taken.insert(l.name);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const AttachedObject& object = objects[i];
    const std::string f = field + "[" + std::to_string(i) + "]";
    if (object.name.empty()) ThrowInvalid(f + ".name is empty: an attached object needs a name");
    if (robot.FindLink(object.name) >= 0) {
      ThrowInvalid(f + ".name = '" + object.name + "' is a link of robot '" + robot.name() + "'; give the object a name of its own");
    }
    if (!taken.insert(object.name).second) ThrowInvalid(f + ".name = '" + object.name + "' is attached twice");
    if (object.link < 0 || object.link >= robot.num_links()) {
      ThrowInvalid(f + ".link = " + std::to_string(object.link) + " is not a link of robot '" + robot.name() + "'");
    }
    if (object.shapes.empty()) ThrowInvalid(f + " has no shapes: give it a box, sphere, cylinder or capsule");
    if (!(std::isfinite(object.mass) && object.mass >= 0.0)) {
      ThrowInvalid(f + ".mass = " + FormatNumber(object.mass) + " must be finite and >= 0 [kg]");
    }
    if (!object.center_of_mass.allFinite()) ThrowInvalid(f + ".center_of_mass must be finite");
    const std::string& parent = robot.links()[static_cast<std::size_t>(object.link)].name;
    Link carried;
    carried.name = object.name;
    carried.collision = object.shapes;
    if (object.mass > 0.0) {
      Inertial load;
      load.mass = object.mass;
      load.com = object.center_of_mass;
      carried.inertial = load;
    }
    carried.parent_joint = static_cast<int>(joints.size());
    Joint fixed;
    fixed.name = object.name + "_attachment";
    fixed.type = JointType::kFixed;
    fixed.parent_link = object.link;
    fixed.child_link = static_cast<int>(links.size());
    links.push_back(std::move(carried));
    joints.push_back(std::move(fixed));
    allowed.emplace_back(parent, object.name);
    for (std::size_t t = 0; t < object.touch_links.size(); ++t) {
      const std::string& touch = object.touch_links[t];
      if (robot.FindLink(touch) < 0) {
        ThrowInvalid(f + ".touch_links[" + std::to_string(t) + "] = '" + touch + "' is not a link of robot '" +
                     robot.name() + "' (links: " + link_names() + ")");
      }
      allowed.emplace_back(touch, object.name);
    }
  }
  return RobotModel::FromTree(robot.name(), std::move(links), std::move(joints), allowed, robot.motion(),
                              robot.load_warnings());
}

}  // namespace chasles
