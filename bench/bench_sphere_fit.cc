// `chasles-bench --section sphere_fit` (issue 25): the sphere fit a robot with meshes gets at
// upload (FitRobotSpheres), timed per robot and per shape, with the reach it proves. Robots: the
// Baxter's published collision geometry (its URDF's 20 cylinders and 5 spheres as written; its 2
// collision meshes are binary files the URDF does not carry, so 0.1 m boxes stand in for them),
// the example UR5 as STL meshes, and a Fetch-like robot whose 21 collision meshes are boxes; then
// every distinct cylinder of the Baxter and reference cylinders alone. Baseline in the same run:
// the fit as it was before cylinders and capsules were covered directly (each shape in turn, a
// cylinder as its circumscribed 24-sided prism through FitSpheres, a capsule as that prism and a
// ball at each end), alternated run by run with the fit as it is, on one thread and on all.

#include "bench_sphere_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan
#include "chasles/collision/mesh.h"
#include "chasles/collision/robot_spheres.h"
#include "chasles/collision/shape_spheres.h"
#include "chasles/collision/sphere_fit.h"
#include "chasles/robot/robot_model.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

/// A closed box mesh of `size` about the origin, 12 triangles.
std::shared_ptr<const TriangleMesh> BoxMesh(const Eigen::Vector3d& size) {
  auto mesh = std::make_shared<TriangleMesh>();
  const Eigen::Vector3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i) {
    mesh->vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh->triangles.emplace_back(f[0], f[1], f[2]);
    mesh->triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

/// The 0.1 m box that stands in for every collision mesh of a URDF given by --urdf.
std::shared_ptr<const TriangleMesh> StandIn(const std::string&) { return BoxMesh(Eigen::Vector3d::Constant(0.1)); }

/// A URDF of one root link and `links` hung from it by fixed joints, each with one collision
/// element: (name, geometry XML, origin xyz).
struct CollisionLink {
  std::string name, geometry, xyz;
};
std::string StarUrdf(const std::string& robot, const std::vector<CollisionLink>& links) {
  std::string urdf = "<robot name=\"" + robot + "\">\n  <link name=\"root\"/>\n";
  for (const CollisionLink& l : links) {
    urdf += "  <link name=\"" + l.name + "\"><collision><origin xyz=\"" + l.xyz + "\"/><geometry>" +
            l.geometry + "</geometry></collision></link>\n";
    urdf += "  <joint name=\"" + l.name + "_joint\" type=\"fixed\"><parent link=\"root\"/><child link=\"" +
            l.name + "\"/></joint>\n";
  }
  return urdf + "</robot>\n";
}

std::string Cylinder(double radius, double length) {
  return "<cylinder radius=\"" + std::to_string(radius) + "\" length=\"" + std::to_string(length) + "\"/>";
}
std::string Sphere(double radius) { return "<sphere radius=\"" + std::to_string(radius) + "\"/>"; }
std::string Mesh(const std::string& file) { return "<mesh filename=\"" + file + "\"/>"; }

/// baxter_description/urdf/baxter.urdf (Rethink Robotics, BSD): every collision element, as
/// written (links, geometry, origins; all its collision origins have rpy 0).
std::shared_ptr<const RobotModel> Baxter() {
  std::vector<CollisionLink> links = {
      {"torso", Mesh("package://baxter_description/meshes/torso/base_link_collision.DAE"), "0 0 0"},
      {"pedestal", Mesh("package://baxter_description/meshes/base/pedestal_link_collision.DAE"), "0 0 0"},
      {"head", Sphere(0.001), "0 0 0"},
      {"sonar_ring", Sphere(0.001), "0 0 0"},
      {"screen", Sphere(0.001), "0 0 0"},
      {"collision_head_link_1", Sphere(0.22), "-0.07 -0.04 0"},
      {"collision_head_link_2", Sphere(0.22), "-0.07 0.04 0"},
  };
  for (const char* side : {"right", "left"}) {
    const std::string s = side;
    const auto add = [&](const char* part, double radius, double length, const char* xyz) {
      links.push_back({s + "_" + part, Cylinder(radius, length), xyz});
    };
    add("upper_shoulder", 0.06, 0.2722, "0 0 0.1361");
    add("lower_shoulder", 0.06, 0.12, "0 0 0");
    add("upper_elbow", 0.06, 0.107, "0 0 -0.0535");
    add("upper_elbow_visual", 0.06, 0.273, "0 0 0.1365");
    add("lower_elbow", 0.06, 0.10, "0 0 0");
    add("upper_forearm", 0.06, 0.088, "0 0 -0.044");
    add("upper_forearm_visual", 0.06, 0.272, "0 0 0.136");
    add("lower_forearm", 0.06, 0.10, "0 0 0");
    add("wrist", 0.06, 0.165, "0 0 0");
    add("hand", 0.04, 0.0464, "0 0 -0.0232");
  }
  return RobotModel::FromUrdfResolvingMeshes(StarUrdf("baxter", links), "", StandIn);
}

/// A Fetch-like mobile manipulator: 21 links (Fetch's link names, sizes of their kind), each
/// collision mesh a box.
std::shared_ptr<const RobotModel> FetchLikeBoxes() {
  struct Part {
    const char* name;
    double x, y, z;
  };
  const Part parts[] = {{"base_link", 0.56, 0.56, 0.36},         {"torso_fixed_link", 0.30, 0.30, 0.40},
                        {"torso_lift_link", 0.28, 0.36, 0.75},   {"bellows_link", 0.12, 0.12, 0.30},
                        {"head_pan_link", 0.15, 0.25, 0.08},     {"head_tilt_link", 0.12, 0.28, 0.12},
                        {"head_camera_link", 0.04, 0.20, 0.05},  {"shoulder_pan_link", 0.22, 0.14, 0.14},
                        {"shoulder_lift_link", 0.16, 0.12, 0.12}, {"upperarm_roll_link", 0.20, 0.11, 0.11},
                        {"elbow_flex_link", 0.16, 0.11, 0.11},   {"forearm_roll_link", 0.20, 0.10, 0.10},
                        {"wrist_flex_link", 0.14, 0.09, 0.09},   {"wrist_roll_link", 0.06, 0.08, 0.08},
                        {"gripper_link", 0.12, 0.16, 0.07},      {"l_gripper_finger_link", 0.06, 0.014, 0.03},
                        {"r_gripper_finger_link", 0.06, 0.014, 0.03}, {"l_wheel_link", 0.12, 0.05, 0.12},
                        {"r_wheel_link", 0.12, 0.05, 0.12},      {"laser_link", 0.06, 0.06, 0.05},
                        {"estop_link", 0.04, 0.04, 0.02}};
  std::vector<CollisionLink> links;
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  for (const Part& p : parts) {
    const std::string file = std::string("package://fetch_like/") + p.name + ".stl";
    links.push_back({p.name, Mesh(file), "0 0 0"});
    meshes[file] = BoxMesh({p.x, p.y, p.z});
  }
  return RobotModel::FromUrdf(StarUrdf("fetch_like", links), "", meshes);
}

std::shared_ptr<const RobotModel> Ur5Meshes(const std::string& examples_dir) {
  const std::string dir = examples_dir + "/robots/";
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  for (const char* link : {"base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
                           "wrist_2_link", "wrist_3_link"}) {
    const std::string file = std::string(link) + "_0.stl";
    meshes["package://ur5_meshes/" + file] = ParseMesh(ReadFile(dir + "ur5_meshes/" + file), Eigen::Vector3d::Ones(), file);
  }
  return RobotModel::FromUrdf(ReadFile(dir + "ur5_meshes.urdf"), ReadFile(dir + "ur5_meshes.srdf"), meshes);
}

/// The 24-sided prism circumscribing a cylinder: how FitRobotSpheres covered cylinders before
/// fitting them directly (the baseline of the per-shape table).
TriangleMesh CircumscribedPrism(double radius, double length) {
  constexpr int kSides = 24;
  TriangleMesh mesh;
  const double outer = radius / std::cos(M_PI / kSides), z = 0.5 * length;
  for (int k = 0; k < kSides; ++k) {
    const double a = 2.0 * M_PI * k / kSides;
    mesh.vertices.emplace_back(outer * std::cos(a), outer * std::sin(a), -z);
    mesh.vertices.emplace_back(outer * std::cos(a), outer * std::sin(a), z);
  }
  mesh.vertices.emplace_back(0.0, 0.0, -z);
  mesh.vertices.emplace_back(0.0, 0.0, z);
  for (int k = 0; k < kSides; ++k) {
    const int a = 2 * k, b = 2 * ((k + 1) % kSides);
    mesh.triangles.emplace_back(a, b, b + 1);
    mesh.triangles.emplace_back(a, b + 1, a + 1);
    mesh.triangles.emplace_back(2 * kSides, b, a);
    mesh.triangles.emplace_back(2 * kSides + 1, a + 1, b + 1);
  }
  return mesh;
}

struct Fit {
  int shapes = 0, spheres = 0;
  double reach = 0.0;
  std::string link;
};

/// FitRobotSpheres as it was before cylinders and capsules were covered directly: one shape after
/// another, cylinders and capsules through the circumscribed prism (capsules plus a ball of their
/// radius at each end, beyond the link's budget), boxes and meshes through FitSpheres.
Fit PrismPathFit(const RobotModel& robot, const RobotSphereOptions& options) {
  Fit out;
  for (const Link& link : robot.links()) {
    int to_fit = 0;
    for (const Shape& shape : link.collision) to_fit += shape.type == ShapeType::kSphere ? 0 : 1;
    SphereFitOptions fit = options.fit;
    fit.max_spheres = std::max(1, options.max_spheres_per_link / std::max(1, to_fit));
    for (const Shape& shape : link.collision) {
      if (shape.type == ShapeType::kSphere) {
        ++out.spheres;
        continue;
      }
      FittedSpheres f;
      double extra = 0.0;
      if (shape.type == ShapeType::kCylinder || shape.type == ShapeType::kCapsule) {
        f = FitSpheres(CircumscribedPrism(shape.radius, shape.length), fit);
        extra = shape.radius * (1.0 / std::cos(M_PI / 24) - 1.0);
        out.spheres += shape.type == ShapeType::kCapsule ? 2 : 0;
      } else if (shape.type == ShapeType::kBox) {
        f = FitSpheres(*BoxMesh(shape.size), fit);
      } else {
        f = FitSpheres(*shape.mesh, fit);
      }
      ++out.shapes;
      out.spheres += static_cast<int>(f.centres.size());
      if (f.reach + extra > out.reach) out.reach = f.reach + extra, out.link = link.name;
    }
  }
  return out;
}

struct Series {
  std::string method;
  Fit fit;
  std::vector<double> seconds;
};

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

}  // namespace

void BenchSphereFit(const SphereFitBenchOptions& options) {
  const int repeats = std::max(1, options.repeats);
  std::vector<std::pair<std::string, std::shared_ptr<const RobotModel>>> robots = {
      {"baxter (published collision geometry, meshes as 0.1 m boxes)", Baxter()},
      {"ur5_meshes (7 STL meshes)", Ur5Meshes(options.examples_dir)},
      {"fetch-like (21 box meshes)", FetchLikeBoxes()},
  };
  for (const std::string& path : options.urdfs) {
    robots.emplace_back(path + " (meshes as 0.1 m boxes)",
                        RobotModel::FromUrdfResolvingMeshes(ReadFile(path), "", StandIn));
  }
  const RobotSphereOptions defaults;
  const int hardware = static_cast<int>(std::thread::hardware_concurrency());
  std::printf("\n## Sphere fit at upload (issue 25): FitRobotSpheres per robot, %d alternated runs of each method "
              "(max_reach %.3f m, %d spheres per link, %d hardware threads)\n\n",
              repeats, defaults.fit.max_reach, defaults.max_spheres_per_link, hardware);
  std::printf("| robot | method | shapes fitted | spheres | reach [mm] (link) | median [s] | min [s] | max [s] | "
              "median / before |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, robot] : robots) {
    std::vector<Series> series(3);
    series[0].method = "FitRobotSpheres, all threads";
    series[1].method = "FitRobotSpheres, 1 thread";
    series[2].method = "before: prism path, 1 thread (baseline)";
    for (int k = 0; k < repeats; ++k) {
      for (std::size_t m = 0; m < series.size(); ++m) {
        RobotSphereOptions o;
        o.threads = m == 1 ? 1 : 0;
        const auto t0 = Clock::now();
        if (m < 2) {
          const RobotSphereFit fit = FitRobotSpheres(*robot, o);
          series[m].seconds.push_back(Seconds(t0));
          series[m].fit = {fit.shapes_fitted, fit.spheres, fit.reach, fit.reach_link};
        } else {
          series[m].fit = PrismPathFit(*robot, o);
          series[m].seconds.push_back(Seconds(t0));
        }
      }
    }
    const double before = QuantileOrNan(series[2].seconds, 0.5);
    for (const Series& s : series) {
      std::printf("| %s | %s | %d | %d | %.1f (%s) | %.3f | %.3f | %.3f | %.3f |\n", name.c_str(), s.method.c_str(),
                  s.fit.shapes, s.fit.spheres, 1e3 * s.fit.reach, s.fit.link.c_str(), QuantileOrNan(s.seconds, 0.5),
                  QuantileOrNan(s.seconds, 0.0), QuantileOrNan(s.seconds, 1.0), QuantileOrNan(s.seconds, 0.5) / before);
    }
  }

  // Each distinct cylinder of the Baxter, and reference ones, alone with a link's budget.
  struct Reference {
    std::string name;
    double radius, length;
  };
  std::vector<Reference> shapes;
  for (const Link& link : robots[0].second->links()) {
    for (const Shape& s : link.collision) {
      if (s.type != ShapeType::kCylinder) continue;
      const bool seen = std::any_of(shapes.begin(), shapes.end(),
                                    [&](const Reference& r) { return r.radius == s.radius && r.length == s.length; });
      if (!seen) shapes.push_back({"baxter " + link.name, s.radius, s.length});
    }
  }
  shapes.push_back({"thin disc", 0.085, 0.01});
  shapes.push_back({"long thin cylinder", 0.02, 0.4});
  shapes.push_back({"wide cylinder", 0.2, 0.5});
  SphereFitOptions fit;
  fit.max_spheres = defaults.max_spheres_per_link;
  std::printf("\n## Each cylinder alone, at most %d spheres, max_reach %.3f m: FitShapeSpheres against the "
              "circumscribed 24-sided prism through FitSpheres (its reach includes the prism's own "
              "r·(1/cos(π/24) − 1)), %d alternated runs\n\n",
              fit.max_spheres, fit.max_reach, repeats);
  std::printf("| shape | radius [m] | length [m] | method | spheres | reach [mm] | median [ms] | min [ms] | max [ms] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const Reference& s : shapes) {
    const TriangleMesh prism = CircumscribedPrism(s.radius, s.length);
    std::vector<double> direct_ms, prism_ms;
    FittedSpheres direct, via_prism;
    for (int k = 0; k < repeats; ++k) {
      auto t0 = Clock::now();
      direct = FitShapeSpheres(Shape::Cylinder(s.radius, s.length), fit);
      direct_ms.push_back(1e3 * Seconds(t0));
      t0 = Clock::now();
      via_prism = FitSpheres(prism, fit);
      prism_ms.push_back(1e3 * Seconds(t0));
    }
    via_prism.reach += s.radius * (1.0 / std::cos(M_PI / 24) - 1.0);
    const auto row = [&](const char* method, const FittedSpheres& f, const std::vector<double>& ms) {
      std::printf("| %s | %.4g | %.4g | %s | %zu | %.2f | %.1f | %.1f | %.1f |\n", s.name.c_str(), s.radius, s.length,
                  method, f.centres.size(), 1e3 * f.reach, QuantileOrNan(ms, 0.5), QuantileOrNan(ms, 0.0),
                  QuantileOrNan(ms, 1.0));
    };
    row("FitShapeSpheres", direct, direct_ms);
    row("before: prism → FitSpheres", via_prism, prism_ms);
  }
  std::printf("\n");
}

}  // namespace chasles
