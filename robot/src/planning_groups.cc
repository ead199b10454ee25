// SRDF planning groups, read with tinyxml as the loader reads the SRDF's pairs.

#include "chasles/robot/planning_groups.h"

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <utility>

#include <tinyxml.h>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

/// Index into robot.joints() of the joint called `name`, or -1.
int FindJoint(const RobotModel& robot, const std::string& name) {
  for (std::size_t j = 0; j < robot.joints().size(); ++j) {
    if (robot.joints()[j].name == name) return static_cast<int>(j);
  }
  return -1;
}

}  // namespace

std::vector<PlanningGroup> ReadPlanningGroups(const RobotModel& robot, std::string_view srdf, bool strict,
                                              std::vector<std::string>* warnings) {
  std::vector<PlanningGroup> out;
  if (srdf.find_first_not_of(" \t\r\n") == std::string_view::npos) return out;
  TiXmlDocument doc;
  doc.Parse(std::string(srdf).c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error()) {
    ThrowInvalid("srdf: malformed XML at line " + std::to_string(doc.ErrorRow()) + ", column " +
                 std::to_string(doc.ErrorCol()) + ": " + doc.ErrorDesc());
  }
  const TiXmlElement* root = doc.RootElement();
  if (root == nullptr) return out;

  const auto skip = [&](const std::string& message) {
    if (strict) ThrowInvalid(message);
    if (warnings != nullptr) warnings->push_back(message + "; the entry is skipped");
  };
  // The group elements by name, in document order.
  std::vector<const TiXmlElement*> elements;
  std::map<std::string, int> by_name;
  for (const TiXmlElement* e = root->FirstChildElement("group"); e != nullptr; e = e->NextSiblingElement("group")) {
    const int index = static_cast<int>(elements.size());
    const char* name = e->Attribute("name");
    if (name == nullptr || *name == '\0') ThrowInvalid("srdf: group[" + std::to_string(index) + "] has no name");
    if (!by_name.emplace(name, index).second) {
      ThrowInvalid("srdf: group[" + std::to_string(index) + "] name = '" + name + "' is the name of group[" +
                   std::to_string(by_name[name]) + "] too");
    }
    elements.push_back(e);
  }

  const auto add_joint = [&](int joint, std::set<int>* dofs) {
    const int dof = robot.joints()[static_cast<std::size_t>(joint)].dof;
    if (dof >= 0) dofs->insert(dof);
  };
  std::map<int, std::set<int>> resolved;
  std::vector<int> state(elements.size(), 0);  // 0 unseen, 1 in progress, 2 done
  std::function<const std::set<int>&(int)> resolve = [&](int g) -> const std::set<int>& {
    if (state[static_cast<std::size_t>(g)] == 2) return resolved[g];
    const TiXmlElement* e = elements[static_cast<std::size_t>(g)];
    const std::string where = "srdf: group '" + std::string(e->Attribute("name")) + "'";
    if (state[static_cast<std::size_t>(g)] == 1) ThrowInvalid(where + " includes itself through its subgroups");
    state[static_cast<std::size_t>(g)] = 1;
    std::set<int> dofs;
    int k = 0;
    for (const TiXmlElement* c = e->FirstChildElement(); c != nullptr; c = c->NextSiblingElement(), ++k) {
      const std::string kind = c->Value();
      const std::string entry = where + " " + kind + "[" + std::to_string(k) + "]";
      if (kind == "joint") {
        const char* name = c->Attribute("name");
        const int joint = name ? FindJoint(robot, name) : -1;
        if (joint < 0) {
          skip(entry + " name = '" + (name ? name : "") + "' is not a joint of robot '" + robot.name() + "'");
          continue;
        }
        add_joint(joint, &dofs);
      } else if (kind == "link") {
        const char* name = c->Attribute("name");
        const int link = name ? robot.FindLink(name) : -1;
        if (link < 0) {
          skip(entry + " name = '" + (name ? name : "") + "' is not a link of robot '" + robot.name() + "'");
          continue;
        }
        const int joint = robot.links()[static_cast<std::size_t>(link)].parent_joint;
        if (joint >= 0) add_joint(joint, &dofs);
      } else if (kind == "chain") {
        const char* base = c->Attribute("base_link");
        const char* tip = c->Attribute("tip_link");
        const int base_link = base ? robot.FindLink(base) : -1;
        const int tip_link = tip ? robot.FindLink(tip) : -1;
        if (base_link < 0 || tip_link < 0) {
          skip(entry + (base_link < 0 ? " base_link = '" + std::string(base ? base : "")
                                      : " tip_link = '" + std::string(tip ? tip : "")) +
               "' is not a link of robot '" + robot.name() + "'");
          continue;
        }
        std::set<int> chain;
        int link = tip_link;
        while (link != base_link) {
          const int joint = robot.links()[static_cast<std::size_t>(link)].parent_joint;
          if (joint < 0) {
            ThrowInvalid(entry + " base_link = '" + base + "' is not an ancestor of tip_link = '" + tip + "'");
          }
          add_joint(joint, &chain);
          link = robot.joints()[static_cast<std::size_t>(joint)].parent_link;
        }
        dofs.insert(chain.begin(), chain.end());
      } else if (kind == "group") {
        const char* name = c->Attribute("name");
        const auto found = name ? by_name.find(name) : by_name.end();
        if (found == by_name.end()) {
          skip(entry + " name = '" + (name ? name : "") + "' is not a group of this SRDF");
          continue;
        }
        const std::set<int>& sub = resolve(found->second);
        dofs.insert(sub.begin(), sub.end());
      }
    }
    state[static_cast<std::size_t>(g)] = 2;
    return resolved[g] = std::move(dofs);
  };
  for (std::size_t g = 0; g < elements.size(); ++g) {
    const std::set<int>& dofs = resolve(static_cast<int>(g));
    const std::string name = elements[g]->Attribute("name");
    if (dofs.empty()) {
      if (warnings != nullptr) warnings->push_back("srdf: group '" + name + "' moves no joint of robot '" + robot.name() + "'; it is skipped");
      continue;
    }
    out.push_back({name, std::vector<int>(dofs.begin(), dofs.end())});
  }
  return out;
}

std::shared_ptr<const RobotModel> HoldJointsOutside(const RobotModel& robot, const std::vector<int>& dofs,
                                                    const Eigen::VectorXd& q) {
  if (q.size() != robot.num_dofs()) {
    ThrowInvalid("HoldJointsOutside: q has " + std::to_string(q.size()) + " values, robot '" + robot.name() +
                 "' has " + std::to_string(robot.num_dofs()) + " joints");
  }
  std::vector<char> moving(static_cast<std::size_t>(robot.num_dofs()), 0);
  for (int dof : dofs) {
    if (dof < 0 || dof >= robot.num_dofs() || moving[static_cast<std::size_t>(dof)]) {
      ThrowInvalid("HoldJointsOutside: joint index " + std::to_string(dof) + " is out of range or repeated");
    }
    moving[static_cast<std::size_t>(dof)] = 1;
  }
  std::vector<Joint> joints = robot.joints();
  for (Joint& joint : joints) {
    if (joint.dof < 0 || moving[static_cast<std::size_t>(joint.dof)]) continue;
    const double value = joint.Position(q);  // a mimic joint's too: m·q[dof] + c
    if (joint.type == JointType::kPrismatic) {
      joint.origin = joint.origin * Eigen::Translation3d(value * joint.axis);
    } else {
      joint.origin = joint.origin * Eigen::AngleAxisd(value, joint.axis);
    }
    joint.type = JointType::kFixed;
    joint.mimic.reset();  // held: it follows nothing
  }
  std::vector<std::pair<std::string, std::string>> allowed;
  const std::vector<Link>& links = robot.links();
  for (int a = 0; a < robot.num_links(); ++a) {
    for (int b = a + 1; b < robot.num_links(); ++b) {
      if (robot.allowed_collisions().IsAllowed(a, b)) allowed.emplace_back(links[a].name, links[b].name);
    }
  }
  return RobotModel::FromTree(robot.name(), links, std::move(joints), allowed, robot.motion());
}

}  // namespace chasles
