#include "chasles/robot/mobile.h"

#include <cmath>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;

void RequirePositive(double value, const std::string& field) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be > 0 and finite");
  }
}

}  // namespace

std::shared_ptr<const RobotModel> RobotFromMobile(const MobileDescription& mobile) {
  const RobotKind kind = mobile.kind;
  if (kind == RobotKind::kArm) {
    ThrowInvalid("mobile.kind must be planar, dubins_car, reeds_shepp_car or free_flyer (got arm)");
  }
  const bool flyer = kind == RobotKind::kFreeFlyer;
  const int translations = flyer ? 3 : 2;
  static const char* kAxis[] = {"x", "y", "z"};
  for (int i = 0; i < translations; ++i) {
    const double lo = mobile.workspace_min[i], hi = mobile.workspace_max[i];
    const std::string a = kAxis[i];
    if (!std::isfinite(lo) || !std::isfinite(hi)) {
      ThrowInvalid("mobile.workspace_min." + a + " = " + FormatNumber(lo) + " and mobile.workspace_max." + a +
                   " = " + FormatNumber(hi) + " must be finite");
    }
    if (!(lo < hi)) {
      ThrowInvalid("mobile.workspace_min." + a + " = " + FormatNumber(lo) + " must be < workspace_max." +
                   a + " = " + FormatNumber(hi));
    }
  }
  RequirePositive(mobile.linear_velocity, "mobile.linear_velocity");
  RequirePositive(mobile.angular_velocity, "mobile.angular_velocity");
  MotionModel motion;
  motion.kind = kind;
  if (IsCar(kind)) {
    RequirePositive(mobile.turning_radius, "mobile.turning_radius");
    motion.turning_radius = mobile.turning_radius;
  }
  if (flyer && (!(mobile.max_tilt > 0.0) || !(mobile.max_tilt <= 1.5))) {
    ThrowInvalid("mobile.max_tilt = " + FormatNumber(mobile.max_tilt) + " must be within (0, 1.5] rad");
  }
  if (mobile.body.collision.empty()) ThrowInvalid("mobile.body has no collision geometry");

  const std::string name = mobile.name.empty() ? "mobile_robot" : mobile.name;
  struct Coordinate {
    const char* joint;
    JointType type;
    Eigen::Vector3d axis;
    double lower, upper, velocity;
  };
  std::vector<Coordinate> coords;
  for (int i = 0; i < translations; ++i) {
    coords.push_back({kAxis[i], JointType::kPrismatic, Eigen::Vector3d::Unit(i), mobile.workspace_min[i],
                      mobile.workspace_max[i], mobile.linear_velocity});
  }
  if (flyer) {
    coords.push_back({"yaw", JointType::kRevolute, Eigen::Vector3d::UnitZ(), -kPi, kPi, mobile.angular_velocity});
    coords.push_back({"pitch", JointType::kRevolute, Eigen::Vector3d::UnitY(), -mobile.max_tilt, mobile.max_tilt,
                      mobile.angular_velocity});
    coords.push_back({"roll", JointType::kRevolute, Eigen::Vector3d::UnitX(), -mobile.max_tilt, mobile.max_tilt,
                      mobile.angular_velocity});
  } else {
    const double range = IsCar(kind) ? 8.0 * kPi : kPi;
    coords.push_back({"theta", JointType::kRevolute, Eigen::Vector3d::UnitZ(), -range, range,
                      mobile.angular_velocity});
  }

  std::vector<Link> links;
  std::vector<Joint> joints;
  Link world;
  world.name = "world";
  links.push_back(world);
  for (size_t i = 0; i < coords.size(); ++i) {
    Joint joint;
    joint.name = coords[i].joint;
    joint.type = coords[i].type;
    joint.parent_link = static_cast<int>(i);
    joint.child_link = static_cast<int>(i + 1);
    joint.axis = coords[i].axis;
    joint.limits.lower = coords[i].lower;
    joint.limits.upper = coords[i].upper;
    joint.limits.velocity = coords[i].velocity;
    joints.push_back(joint);
    Link link;
    link.name = i + 1 == coords.size() ? std::string("body") : std::string(coords[i].joint) + "_link";
    link.parent_joint = static_cast<int>(i);
    if (i + 1 == coords.size()) {
      link.collision = mobile.body.collision;
      link.inertial = mobile.body.inertial;
    }
    links.push_back(std::move(link));
  }
  return RobotModel::FromTree(name, std::move(links), std::move(joints), {}, motion);
}

}  // namespace chasles
