#pragma once
// Helpers shared by the collision tests: example files, JSON scenes, random configurations.

#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include "chasles/collision/mesh.h"
#include "chasles/collision/scene.h"
#include "chasles/robot/robot_model.h"
#include "chasles/v1/chasles.pb.h"
#include "../read_file.h"

namespace chasles::test {

inline std::string ExamplePath(const std::string& rel) {
  return std::string(CHASLES_SOURCE_DIR) + "/examples/" + rel;
}

inline Eigen::Isometry3d PoseFromProto(const v1::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << p.position().x(), p.position().y(), p.position().z();
  const auto& q = p.orientation();
  if (q.x() != 0 || q.y() != 0 || q.z() != 0 || q.w() != 0) {
    t.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  }
  return t;
}

/// Loads a chasles.v1.Scene JSON file into a Scene (the test's own small converter, so the
/// collision tests do not depend on server/).
inline std::shared_ptr<Scene> LoadScene(const std::string& rel) {
  v1::Scene msg;
  const auto status = google::protobuf::util::JsonStringToMessage(ReadFile(ExamplePath(rel)), &msg);
  EXPECT_TRUE(status.ok()) << rel << ": " << status.ToString();
  auto scene = std::make_shared<Scene>();
  for (const auto& b : msg.boxes()) {
    scene->AddObject({b.name(), Shape::Box({b.size().x(), b.size().y(), b.size().z()}, PoseFromProto(b.pose()))});
  }
  for (const auto& s : msg.spheres()) scene->AddObject({s.name(), Shape::Sphere(s.radius(), PoseFromProto(s.pose()))});
  for (const auto& c : msg.cylinders()) {
    scene->AddObject({c.name(), Shape::Cylinder(c.radius(), c.length(), PoseFromProto(c.pose()))});
  }
  for (const auto& c : msg.capsules()) {
    scene->AddObject({c.name(), Shape::Capsule(c.radius(), c.length(), PoseFromProto(c.pose()))});
  }
  for (int i = 0; i < msg.meshes_size(); ++i) {
    const auto& m = msg.meshes(i);
    Eigen::Vector3d scale(m.scale().x(), m.scale().y(), m.scale().z());
    if (scale.isZero()) scale.setOnes();
    Shape shape;
    shape.type = ShapeType::kMesh;
    shape.mesh = ParseMesh(m.data(), scale, "scene.meshes[" + std::to_string(i) + "].data");
    shape.pose = PoseFromProto(m.pose());
    scene->AddObject({m.name(), shape});
  }
  for (int i = 0; i < msg.octomaps_size(); ++i) {
    const auto& o = msg.octomaps(i);
    scene->AddOctoMap(o.name(), o.data(), PoseFromProto(o.pose()),
                      "scene.octomaps[" + std::to_string(i) + "].data");
  }
  return scene;
}

inline std::shared_ptr<const RobotModel> LoadRobot(const std::string& name) {
  const std::string urdf = ReadFile(ExamplePath("robots/" + name + ".urdf"));
  std::ifstream srdf_file(ExamplePath("robots/" + name + ".srdf"));
  std::string srdf;
  if (srdf_file) srdf = ReadFile(ExamplePath("robots/" + name + ".srdf"));
  return RobotModel::FromUrdf(urdf, srdf);
}

/// The robot's collision sphere centres in their link frames, in the checker's sphere order
/// (link order, then shape order), and each one's link.
inline void SphereCentres(const RobotModel& robot, std::vector<Eigen::Vector3d>* centres, std::vector<int>* link_of) {
  for (int l = 0; l < robot.num_links(); ++l) {
    for (const Shape& s : robot.links()[l].collision) {
      centres->push_back(s.pose.translation());
      link_of->push_back(l);
    }
  }
}

inline Eigen::VectorXd RandomConfig(const RobotModel& robot, std::mt19937_64& rng) {
  Eigen::VectorXd q(robot.num_dofs());
  for (int i = 0; i < q.size(); ++i) {
    std::uniform_real_distribution<double> u(robot.lower_limits()[i], robot.upper_limits()[i]);
    q[i] = u(rng);
  }
  return q;
}

inline Eigen::VectorXd PandaReady() {
  Eigen::VectorXd q(7);
  q << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  return q;
}

inline Eigen::VectorXd Ur5Up() {
  Eigen::VectorXd q(6);
  q << 0, -1.571, 0, -1.571, 0, 0;
  return q;
}

/// A cube of half side `half` [m] as a 12-triangle mesh at `pose` (centred on its origin).
inline Shape CubeMeshShape(double half, const Eigen::Isometry3d& pose) {
  auto mesh = std::make_shared<TriangleMesh>();
  for (int i = 0; i < 8; ++i) {
    mesh->vertices.emplace_back(i & 1 ? half : -half, i & 2 ? half : -half, i & 4 ? half : -half);
  }
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : faces) mesh->triangles.emplace_back(f[0], f[1], f[2]);
  Shape shape;
  shape.type = ShapeType::kMesh;
  shape.mesh = mesh;
  shape.pose = pose;
  return shape;
}

/// A one-link robot: a fixed base link with one prismatic joint along x carrying `shape`.
inline std::shared_ptr<const RobotModel> SliderRobot(const Shape& shape) {
  Link base;
  base.name = "base";
  Link mover;
  mover.name = "mover";
  mover.parent_joint = 0;
  mover.collision.push_back(shape);
  Joint j;
  j.name = "slide_x";
  j.type = JointType::kPrismatic;
  j.parent_link = 0;
  j.child_link = 1;
  j.axis = Eigen::Vector3d::UnitX();
  j.limits = {-5.0, 5.0, 1.0, 0.0};
  j.dof = 0;
  return RobotModel::FromTree("slider", {base, mover}, {j});
}

}  // namespace chasles::test
