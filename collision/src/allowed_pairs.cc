#include <string>
#include <vector>

#include "chasles/robot/error.h"
#include "checker_impl.h"

namespace chasles::detail {
namespace {
/// At most 20 names joined by ", ", then how many more; "none" when there are none.
template <typename Range, typename Name>
std::string NameList(const Range& items, Name name) {
  constexpr std::size_t kMaxNames = 20;
  std::string out;
  std::size_t n = 0;
  for (const auto& item : items) {
    if (n++ < kMaxNames) out += (out.empty() ? "" : ", ") + name(item);
  }
  if (n > kMaxNames) out += ", … (" + std::to_string(n - kMaxNames) + " more)";
  return n == 0 ? "none" : out;
}

}  // namespace

SceneAllowances ResolveSceneAllowances(const RobotModel& robot, const Scene& scene) {
  SceneAllowances out;
  const std::vector<AllowedCollision>& pairs = scene.allowed_collisions();
  if (pairs.empty()) return out;
  const int nl = robot.num_links();
  out.objects.resize(scene.objects().size());
  out.maps.resize(scene.occupancy_maps().size());
  const auto links = [&] { return NameList(robot.links(), [](const Link& l) { return l.name; }); };
  const auto obstacles = [&] {
    return "scene objects: " + NameList(scene.objects(), [](const SceneObject& o) { return o.name; }) +
           "; OctoMaps: " + NameList(scene.occupancy_maps(), [](const OccupancyMap& m) { return m.name; });
  };
  const auto allow = [nl](std::vector<char>* obstacle_links, int link) {
    if (obstacle_links->empty()) obstacle_links->assign(nl, 0);
    (*obstacle_links)[link] = 1;
  };
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::string field = "scene.allowed_collisions[" + std::to_string(i) + "]";
    const AllowedCollision& pair = pairs[i];
    const int a = robot.FindLink(pair.link);
    if (a < 0) {
      bool obstacle = false;
      for (const SceneObject& o : scene.objects()) obstacle = obstacle || o.name == pair.link;
      for (const OccupancyMap& m : scene.occupancy_maps()) obstacle = obstacle || m.name == pair.link;
      ThrowInvalid(field + ".link1 = '" + pair.link + "' is not a link of robot '" + robot.name() + "' (links: " +
                   links() + ")" +
                   (obstacle ? "; it names an obstacle of the scene: link1 must be the robot link, link2 the obstacle"
                             : ""));
    }
    bool found = false;
    const int b = robot.FindLink(pair.other);
    if (b >= 0) {
      if (out.self.empty()) out.self.assign(static_cast<std::size_t>(nl) * nl, 0);
      out.self[static_cast<std::size_t>(a) * nl + b] = out.self[static_cast<std::size_t>(b) * nl + a] = 1;
      found = true;
    }
    for (std::size_t j = 0; j < scene.objects().size(); ++j) {
      if (scene.objects()[j].name != pair.other) continue;
      allow(&out.objects[j], a);
      found = true;
    }
    for (std::size_t j = 0; j < scene.occupancy_maps().size(); ++j) {
      if (scene.occupancy_maps()[j].name != pair.other) continue;
      allow(&out.maps[j], a);
      found = true;
    }
    if (!found) {
      ThrowInvalid(field + ".link2 = '" + pair.other + "' is neither a link of robot '" + robot.name() +
                   "' nor an object or OctoMap of the scene (links: " + links() + "; " + obstacles() + ")");
    }
  }
  return out;
}

}  // namespace chasles::detail
