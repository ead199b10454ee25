// Scene::InsertPointCloud: ray-casting insertion into a copy of a scene's OctoMap (or a new map),
// world -> map frame, the old scene unchanged, validation messages, and the effect on the
// collision checker. ExampleMaps: the mobile-robot and drone maps in examples/scenes keep their
// documented start/goal positions free and connected.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/scene.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

const octomap::OcTreeNode* Search(const octomap::OcTree& tree, const Eigen::Vector3d& p) {
  return tree.search(static_cast<double>(p.x()), static_cast<double>(p.y()), static_cast<double>(p.z()));
}

bool Occupied(const octomap::OcTree& tree, const Eigen::Vector3d& p) {
  const octomap::OcTreeNode* node = Search(tree, p);
  return node != nullptr && tree.isNodeOccupied(node);
}

bool KnownFree(const octomap::OcTree& tree, const Eigen::Vector3d& p) {
  const octomap::OcTreeNode* node = Search(tree, p);
  return node != nullptr && !tree.isNodeOccupied(node);
}

void Append(std::vector<double>* points, const Eigen::Vector3d& p) {
  points->insert(points->end(), {p.x(), p.y(), p.z()});
}

/// A square patch of points on the plane x = `x`, at voxel centres of a 0.05 m map:
/// y, z in {0.025 + 0.05 k : k = -3..2}.
std::vector<double> Patch(double x, double scale = 1.0) {
  std::vector<double> points;
  for (int j = -3; j < 3; ++j) {
    for (int k = -3; k < 3; ++k) Append(&points, Eigen::Vector3d(x, scale * (0.025 + 0.05 * j), scale * (0.025 + 0.05 * k)));
  }
  return points;
}

/// The error InsertPointCloud throws (code checked), or "" when it succeeds.
std::string InsertError(const Scene& scene, const PointCloudInsertion& in, ErrorCode expected) {
  try {
    scene.InsertPointCloud(in);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), expected) << e.what();
    return e.what();
  }
  return "";
}

TEST(PointCloud, EmptySceneGetsANewMapCalledPointsAtTheDefaultResolution) {
  const Scene empty;
  PointCloudInsertion in;
  in.points = Patch(1.025);
  PointCloudInsertionStats stats;
  const Scene updated = empty.InsertPointCloud(in, &stats);

  EXPECT_TRUE(empty.occupancy_maps().empty());  // the old scene is a value: unchanged
  ASSERT_EQ(updated.occupancy_maps().size(), 1u);
  const OccupancyMap& map = updated.occupancy_maps()[0];
  EXPECT_EQ(map.name, "points");
  EXPECT_TRUE(map.pose.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_DOUBLE_EQ(map.tree->getResolution(), 0.05);
  EXPECT_EQ(stats.octomap, "points");
  EXPECT_TRUE(stats.created);
  EXPECT_EQ(stats.points_inserted, 36u);
  EXPECT_EQ(stats.occupied_leaves, 36u);  // one end cell per point (distinct cells)
  EXPECT_DOUBLE_EQ(stats.resolution, 0.05);
  EXPECT_GE(stats.seconds, 0.0);
  for (std::size_t i = 0; i < in.points.size(); i += 3) {
    const Eigen::Vector3d p(in.points[i], in.points[i + 1], in.points[i + 2]);
    EXPECT_TRUE(Occupied(*map.tree, p)) << p.transpose();
    EXPECT_TRUE(KnownFree(*map.tree, 0.5 * p)) << "the ray to " << p.transpose() << " clears its middle";
  }
  EXPECT_EQ(Search(*map.tree, Eigen::Vector3d(-1, 0, 0)), nullptr);  // never observed: unknown

  in.resolution = 0.1;
  EXPECT_DOUBLE_EQ(empty.InsertPointCloud(in).occupancy_maps()[0].tree->getResolution(), 0.1);
}

TEST(PointCloud, ExistingMapIsCopiedAndPointsGoIntoItsFrame) {
  // A map posed at (1, 2, 0.5), rotated 90 degrees about z, holding one occupied voxel.
  auto tree = std::make_shared<octomap::OcTree>(0.05);
  tree->updateNode(octomap::point3d(0.525f, 0.025f, 0.025f), true);
  OccupancyMap original;
  original.name = "lidar";
  original.tree = tree;
  original.pose = Eigen::Translation3d(1, 2, 0.5) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  Scene scene;
  scene.AddObject({"box", Shape::Box({0.1, 0.1, 0.1}, Eigen::Isometry3d(Eigen::Translation3d(5, 5, 5)))});
  scene.AddOccupancyMap(original);
  const std::size_t leaves_before = tree->getNumLeafNodes();

  const Eigen::Vector3d world(0.325, 2.725, 0.825);  // map frame: R^T (world - t) = (0.725, 0.675, 0.325)
  const Eigen::Vector3d sensor(1.0, 2.0, 0.5);  // the map's origin
  PointCloudInsertion in;
  Append(&in.points, world);
  in.sensor_origin = sensor;
  in.resolution = 0.2;  // ignored: the map exists
  PointCloudInsertionStats stats;
  const Scene updated = scene.InsertPointCloud(in, &stats);

  EXPECT_EQ(stats.octomap, "lidar");
  EXPECT_FALSE(stats.created);
  EXPECT_EQ(stats.points_inserted, 1u);
  EXPECT_EQ(stats.occupied_leaves, 2u);
  EXPECT_DOUBLE_EQ(stats.resolution, 0.05);
  ASSERT_EQ(updated.occupancy_maps().size(), 1u);
  ASSERT_EQ(updated.objects().size(), 1u);
  const OccupancyMap& map = updated.occupancy_maps()[0];
  EXPECT_NE(map.tree.get(), tree.get());
  EXPECT_TRUE(map.pose.isApprox(original.pose));
  const Eigen::Vector3d in_map = original.pose.inverse() * world;
  EXPECT_NEAR(in_map.x(), 0.725, 1e-12);
  EXPECT_NEAR(in_map.y(), 0.675, 1e-12);
  EXPECT_NEAR(in_map.z(), 0.325, 1e-12);
  EXPECT_TRUE(Occupied(*map.tree, in_map));
  EXPECT_TRUE(KnownFree(*map.tree, 0.5 * in_map));
  EXPECT_TRUE(Occupied(*map.tree, Eigen::Vector3d(0.525, 0.025, 0.025)));
  // The original tree, still shared by `scene`, is untouched.
  EXPECT_EQ(scene.occupancy_maps()[0].tree.get(), tree.get());
  EXPECT_EQ(tree->getNumLeafNodes(), leaves_before);
  EXPECT_EQ(Search(*tree, in_map), nullptr);
}

TEST(PointCloud, RaysThroughOccupiedCellsClearThem) {
  PointCloudInsertion first;
  first.points = Patch(1.025);
  const Scene one = Scene().InsertPointCloud(first);
  const octomap::OcTree& t1 = *one.occupancy_maps()[0].tree;
  const Eigen::Vector3d cell(1.025, 0.025, 0.025);
  ASSERT_TRUE(Occupied(t1, cell));
  const float hit_log_odds = Search(t1, cell)->getLogOdds();

  // The same directions, three times as far (again voxel centres): every ray passes through the
  // centre of a first-patch cell.
  PointCloudInsertion second;
  second.points = Patch(3.075, 3.0);
  Scene scene = one;
  std::vector<float> log_odds;
  for (int pass = 0; pass < 3; ++pass) {
    scene = scene.InsertPointCloud(second);
    log_odds.push_back(Search(*scene.occupancy_maps()[0].tree, cell)->getLogOdds());
  }
  EXPECT_LT(log_odds[0], hit_log_odds);
  EXPECT_LT(log_odds[1], log_odds[0]);
  // OctoMap's default sensor model (hit 0.7, miss 0.4): one hit outweighs two misses, not three.
  const octomap::OcTree& t3 = *scene.occupancy_maps()[0].tree;
  for (std::size_t i = 0; i < first.points.size(); i += 3) {
    const Eigen::Vector3d p(first.points[i], first.points[i + 1], first.points[i + 2]);
    EXPECT_TRUE(KnownFree(t3, p)) << "first-cloud cell " << p.transpose() << " should be free after three passes";
    EXPECT_TRUE(Occupied(t3, 3.0 * p));
  }
  EXPECT_TRUE(Occupied(t1, cell)) << "the first scene keeps its own map";
}

TEST(PointCloud, MaxRangeCutsRaysAndLeavesTheirEndsUnmarked) {
  PointCloudInsertion in;
  Append(&in.points, Eigen::Vector3d(2.025, 0.025, 0.025));   // 2.025 m away: cut at 1 m
  Append(&in.points, Eigen::Vector3d(0.025, 0.525, 0.025));   // 0.525 m away: kept
  in.max_range = 1.0;
  PointCloudInsertionStats stats;
  const Scene scene = Scene().InsertPointCloud(in, &stats);
  const octomap::OcTree& tree = *scene.occupancy_maps()[0].tree;
  EXPECT_EQ(stats.points_inserted, 2u);
  EXPECT_EQ(stats.occupied_leaves, 1u);
  EXPECT_EQ(Search(tree, Eigen::Vector3d(2.025, 0.025, 0.025)), nullptr);
  EXPECT_EQ(Search(tree, Eigen::Vector3d(1.525, 0.025, 0.025)), nullptr);
  EXPECT_TRUE(KnownFree(tree, Eigen::Vector3d(0.575, 0.025, 0.025)));
  EXPECT_TRUE(Occupied(tree, Eigen::Vector3d(0.025, 0.525, 0.025)));
}

TEST(PointCloud, InvalidInputNamesFieldIndexValueAndRule) {
  Scene scene;
  PointCloudInsertion in;
  in.points = {0, 0, 1, 0, 0, 2, 0};
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument),
            "points has 7 values, must be a multiple of 3 (x, y, z triples)");
  in.points = {0, 0, 1, 0, std::nan(""), 2};
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument), "points[4] = nan must be finite (point 1, y)");
  in.points = {0, 0, 1, 0, 0, 2};
  in.sensor_origin.z() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument), "sensor_origin.z = inf must be finite");
  in.sensor_origin.setZero();
  in.max_range = -0.5;
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument),
            "max_range = -0.5 must be finite and >= 0 (0 = unlimited)");
  in.max_range = 0.0;
  for (double resolution : {0.0005, 11.0, -1.0}) {
    in.resolution = resolution;
    EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument),
              "resolution = " + FormatNumber(resolution) + " must be within [0.001, 10] (0 = 0.05)");
  }
  in.resolution = 0.0;
  in.points = {0, 0, 1, 0, 5000, 2};  // beyond +-1638.4 m at 0.05 m
  const std::string range = InsertError(scene, in, ErrorCode::kInvalidArgument);
  EXPECT_NE(range.find("points[3..5] (point 1) = (0, 5000, 2)"), std::string::npos) << range;
  EXPECT_NE(range.find("[-1638.4, 1638.4) m of map 'points'"), std::string::npos) << range;
  in.max_range = 10.0;  // the ray is cut at 10 m: inside the key range
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument), "");

  in = PointCloudInsertion();
  in.points = {0, 0, 1};
  in.octomap = "lidar";
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kNotFound),
            "octomap = 'lidar' names no OctoMap of the scene (it has none; leave octomap empty to create a "
            "new map 'points')");
  auto tree = std::make_shared<octomap::OcTree>(0.05);
  scene.AddOccupancyMap({"a", tree, Eigen::Isometry3d::Identity()});
  scene.AddOccupancyMap({"b", tree, Eigen::Isometry3d::Identity()});
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kNotFound),
            "octomap = 'lidar' names no OctoMap of the scene (its maps: 'a', 'b')");
  in.octomap.clear();
  EXPECT_EQ(InsertError(scene, in, ErrorCode::kInvalidArgument),
            "octomap is empty but the scene has 2 OctoMaps ('a', 'b'): name the one to update");
  in.octomap = "b";
  PointCloudInsertionStats stats;
  const Scene updated = scene.InsertPointCloud(in, &stats);
  EXPECT_EQ(stats.octomap, "b");
  EXPECT_EQ(updated.occupancy_maps()[0].tree.get(), tree.get());
  EXPECT_NE(updated.occupancy_maps()[1].tree.get(), tree.get());
}

TEST(PointCloud, PointsOnTheArmPutAValidStartInCollision) {
  const auto robot = test::LoadRobot("panda");
  const Eigen::VectorXd ready = test::PandaReady();
  const auto empty = std::make_shared<const Scene>();
  ASSERT_TRUE(CollisionChecker(robot, empty).IsValid(ready));

  // Points at the link origins of the ready pose (inside the links' collision spheres), seen
  // from a sensor 1.5 m away in front of the robot.
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(ready, &poses);
  PointCloudInsertion in;
  for (std::size_t l = 3; l < poses.size(); ++l) Append(&in.points, poses[l].translation());
  in.sensor_origin = Eigen::Vector3d(1.5, 0.0, 1.0);
  const auto cluttered = std::make_shared<const Scene>(empty->InsertPointCloud(in));
  const CollisionChecker checker(robot, cluttered);
  const CollisionResult result = checker.Check(ready);
  EXPECT_TRUE(result.in_collision);
  EXPECT_FALSE(result.self_collision);
  EXPECT_EQ(result.other, "points");
  EXPECT_FALSE(checker.IsValid(ready));

  // A cloud well away from the arm (a wall 1.2 m in front) leaves it valid.
  PointCloudInsertion wall;
  for (int j = -5; j <= 5; ++j) {
    for (int k = 0; k <= 10; ++k) Append(&wall.points, Eigen::Vector3d(1.2, 0.1 * j, 0.1 * k));
  }
  wall.sensor_origin = Eigen::Vector3d(0.0, 0.0, 1.5);
  const auto walled = std::make_shared<const Scene>(empty->InsertPointCloud(wall));
  EXPECT_TRUE(CollisionChecker(robot, walled).IsValid(ready));
}

// --- Example maps for mobile robots and drones (examples/scenes/README.md) ---------------------

/// The occupied finest voxels of a map with an identity pose, as centres.
std::vector<Eigen::Vector3d> OccupiedVoxels(const octomap::OcTree& tree) {
  std::vector<Eigen::Vector3d> out;
  const double res = tree.getResolution();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const int n = static_cast<int>(std::lround(it.getSize() / res));
    const Eigen::Vector3d corner = Eigen::Vector3d(it.getX(), it.getY(), it.getZ()) -
                                   Eigen::Vector3d::Constant(0.5 * it.getSize() - 0.5 * res);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) out.push_back(corner + res * Eigen::Vector3d(i, j, k));
      }
    }
  }
  return out;
}

/// Distance from `p` to the nearest occupied voxel (its cube, not its centre) [m].
double Clearance(const std::vector<Eigen::Vector3d>& voxels, double res, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& v : voxels) {
    best = std::min(best, ((p - v).cwiseAbs() - Eigen::Vector3d::Constant(0.5 * res)).cwiseMax(0.0).norm());
  }
  return best;
}

/// A grid of cells (the map's voxels) over [lo, hi] whose centres lie farther than `radius`
/// from every occupied voxel cube; BFS over 6-neighbours (4 when the grid is one cell tall).
class FreeSpace {
 public:
  FreeSpace(const std::vector<Eigen::Vector3d>& voxels, double res, const Eigen::Vector3d& lo,
            const Eigen::Vector3d& hi, double radius)
      : res_(res), lo_(lo) {
    for (int a = 0; a < 3; ++a) n_[a] = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) / res)));
    blocked_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], 0);
    const int reach = static_cast<int>(std::ceil(radius / res)) + 1;
    for (const Eigen::Vector3d& v : voxels) {
      int c[3];
      for (int a = 0; a < 3; ++a) c[a] = static_cast<int>(std::floor((v[a] - lo_[a]) / res));
      int from[3], to[3];
      for (int a = 0; a < 3; ++a) {
        from[a] = std::max(0, c[a] - reach);
        to[a] = std::min(n_[a] - 1, c[a] + reach);
      }
      for (int i = from[0]; i <= to[0]; ++i) {
        for (int j = from[1]; j <= to[1]; ++j) {
          for (int k = from[2]; k <= to[2]; ++k) {
            const Eigen::Vector3d d = ((Centre(i, j, k) - v).cwiseAbs() - Eigen::Vector3d::Constant(0.5 * res));
            if (d.cwiseMax(0.0).norm() <= radius) blocked_[Index(i, j, k)] = 1;
          }
        }
      }
    }
  }
  /// Blocks every cell whose centre is inside the box [a, b].
  void Block(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    for (int i = 0; i < n_[0]; ++i) {
      for (int j = 0; j < n_[1]; ++j) {
        for (int k = 0; k < n_[2]; ++k) {
          const Eigen::Vector3d c = Centre(i, j, k);
          if ((c.array() >= a.array()).all() && (c.array() <= b.array()).all()) blocked_[Index(i, j, k)] = 1;
        }
      }
    }
  }
  bool Free(const Eigen::Vector3d& p) const {
    const auto c = Cell(p);
    return Inside(c[0], c[1], c[2]) && !blocked_[Index(c[0], c[1], c[2])];
  }
  /// The cells reachable from `start` (0 = not reached).
  std::vector<char> Reach(const Eigen::Vector3d& start) const {
    std::vector<char> seen(blocked_.size(), 0);
    if (!Free(start)) return seen;
    const auto s = Cell(start);
    std::deque<std::array<int, 3>> queue{{s[0], s[1], s[2]}};
    seen[Index(s[0], s[1], s[2])] = 1;
    static const int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    while (!queue.empty()) {
      const auto c = queue.front();
      queue.pop_front();
      for (const auto& d : kSteps) {
        const int i = c[0] + d[0], j = c[1] + d[1], k = c[2] + d[2];
        if (!Inside(i, j, k) || blocked_[Index(i, j, k)] || seen[Index(i, j, k)]) continue;
        seen[Index(i, j, k)] = 1;
        queue.push_back({i, j, k});
      }
    }
    return seen;
  }
  bool Connected(const std::vector<char>& reach, const Eigen::Vector3d& p) const {
    const auto c = Cell(p);
    return Inside(c[0], c[1], c[2]) && reach[Index(c[0], c[1], c[2])];
  }

 private:
  std::array<int, 3> Cell(const Eigen::Vector3d& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a) c[a] = n_[a] == 1 ? 0 : static_cast<int>(std::floor((p[a] - lo_[a]) / res_));
    return c;
  }
  Eigen::Vector3d Centre(int i, int j, int k) const {
    Eigen::Vector3d c = lo_ + res_ * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
    if (n_[2] == 1) c.z() = lo_.z();
    return c;
  }
  bool Inside(int i, int j, int k) const { return i >= 0 && j >= 0 && k >= 0 && i < n_[0] && j < n_[1] && k < n_[2]; }
  std::size_t Index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * n_[1] + j) * n_[0] + i;
  }
  double res_;
  Eigen::Vector3d lo_;
  int n_[3];
  std::vector<char> blocked_;
};

struct ExampleMap {
  std::vector<Eigen::Vector3d> voxels;
  double resolution = 0.0;
};

ExampleMap LoadExampleMap(const std::string& name, double resolution) {
  const auto scene = test::LoadScene("scenes/" + name + "_octomap.json");
  EXPECT_EQ(scene->occupancy_maps().size(), 1u);
  EXPECT_TRUE(scene->objects().empty());
  const OccupancyMap& map = scene->occupancy_maps().at(0);
  EXPECT_EQ(map.name, name);
  EXPECT_TRUE(map.pose.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_DOUBLE_EQ(map.tree->getResolution(), resolution);
  return {OccupiedVoxels(*map.tree), map.tree->getResolution()};
}

// Mobile bases: the body spans z 0.05..0.45 (examples/robots/mobile_base.json); a position is
// checked at z = 0.25 against the walls (all taller than 0.45 m, so this is the planar distance).
constexpr double kBaseHeight = 0.25;
constexpr double kMargin = 0.3;  // [m] clearance every documented start/goal keeps

TEST(ExampleMaps, MazeCorridorsAdmitARoundBaseAndTheDocumentedStartGoalAreFree) {
  const ExampleMap maze = LoadExampleMap("maze", 0.05);
  const Eigen::Vector3d start(0.7, 0.7, kBaseHeight), goal(7.3, 7.3, kBaseHeight);
  for (const Eigen::Vector3d& p : {start, goal}) {
    const double clearance = Clearance(maze.voxels, maze.resolution, p);
    EXPECT_GT(clearance, kMargin) << p.transpose();
    std::printf("maze (%.2f, %.2f): clearance %.3f m\n", p.x(), p.y(), clearance);
  }
  // Planar free space of a round base of radius 0.3 at the base's height: every cell centre
  // of the 6 x 6 maze (every corridor, dead ends included) is reachable from the start.
  const FreeSpace space(maze.voxels, maze.resolution, Eigen::Vector3d(0, 0, kBaseHeight),
                        Eigen::Vector3d(8, 8, kBaseHeight), 0.3);
  const auto reach = space.Reach(start);
  const double lines[] = {0.1, 1.3, 2.7, 3.9, 5.3, 6.7, 7.9};  // wall centre lines (maze.json)
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d centre(0.5 * (lines[i] + lines[i + 1]), 0.5 * (lines[j] + lines[j + 1]), kBaseHeight);
      EXPECT_TRUE(space.Connected(reach, centre)) << "maze cell " << i << ", " << j;
    }
  }
  // The straight line is blocked (the path needs turns).
  bool blocked = false;
  for (double t = 0.0; t <= 1.0; t += 0.001) blocked = blocked || !space.Free(start + t * (goal - start));
  EXPECT_TRUE(blocked);
}

TEST(ExampleMaps, OfficeCorridorReachesTheRoomGoalThroughADoor) {
  const ExampleMap office = LoadExampleMap("office", 0.05);
  const Eigen::Vector3d start(1.0, 4.0, kBaseHeight), goal(10.5, 1.5, kBaseHeight);
  for (const Eigen::Vector3d& p : {start, goal}) {
    const double clearance = Clearance(office.voxels, office.resolution, p);
    EXPECT_GT(clearance, kMargin) << p.transpose();
    std::printf("office (%.2f, %.2f): clearance %.3f m\n", p.x(), p.y(), clearance);
  }
  // Nothing but the door's own wall lies within 1.0 m of a door gap (x0..x1 on the line y).
  struct Door {
    double x0, x1, y;
  };
  for (const Door& door : {Door{2.5, 3.5, 3.1}, Door{8.0, 9.0, 3.1}, Door{1.5, 2.5, 4.9}, Door{9.0, 10.0, 4.9}}) {
    int near = 0;
    for (const Eigen::Vector3d& v : office.voxels) {
      const double dx = std::max({door.x0 - v.x(), v.x() - door.x1, 0.0});
      if (std::hypot(dx, v.y() - door.y) < 1.0 && std::abs(v.y() - door.y) > 0.1) ++near;
    }
    EXPECT_EQ(near, 0) << "door at x " << door.x0 << ".." << door.x1 << ", y " << door.y;
  }
  // The mobile base turning in place sweeps a disc of radius 0.35: still connected.
  FreeSpace space(office.voxels, office.resolution, Eigen::Vector3d(0, 0, kBaseHeight),
                  Eigen::Vector3d(12, 8, kBaseHeight), 0.35);
  EXPECT_TRUE(space.Connected(space.Reach(start), goal));
  // Every door (1.0 m gap) is passable for that disc: each room's centre is reachable.
  for (const Eigen::Vector3d& room : {Eigen::Vector3d(3.0, 2.2, kBaseHeight), Eigen::Vector3d(9.5, 2.0, kBaseHeight),
                                      Eigen::Vector3d(2.0, 5.8, kBaseHeight), Eigen::Vector3d(9.5, 5.8, kBaseHeight)}) {
    EXPECT_TRUE(space.Connected(space.Reach(start), room)) << room.transpose();
  }
  // Closing the south-east room's door disconnects the goal.
  space.Block(Eigen::Vector3d(7.9, 2.9, 0), Eigen::Vector3d(9.1, 3.3, 1));
  EXPECT_FALSE(space.Connected(space.Reach(start), goal));
}

TEST(ExampleMaps, DroneCourseIsCrossedOnlyThroughTheWindow) {
  const ExampleMap course = LoadExampleMap("drone_course", 0.1);
  const Eigen::Vector3d start(1.0, 5.0, 1.5), goal(9.0, 5.0, 2.5);
  for (const Eigen::Vector3d& p : {start, goal}) {
    const double clearance = Clearance(course.voxels, course.resolution, p);
    EXPECT_GT(clearance, kMargin) << p.transpose();
    std::printf("drone_course (%.2f, %.2f, %.2f): clearance %.3f m\n", p.x(), p.y(), p.z(), clearance);
  }
  // The drone's body fits in a sphere of radius 0.33 (examples/robots/drone.json); its
  // workspace keeps z in [0.3, 3.7].
  FreeSpace space(course.voxels, course.resolution, Eigen::Vector3d(0, 0, 0.3), Eigen::Vector3d(10, 10, 3.7), 0.33);
  EXPECT_TRUE(space.Connected(space.Reach(start), goal));
  space.Block(Eigen::Vector3d(4.5, 4.3, 1.3), Eigen::Vector3d(5.5, 5.7, 2.7));  // close the window
  EXPECT_FALSE(space.Connected(space.Reach(start), goal));
}

}  // namespace
}  // namespace chasles
