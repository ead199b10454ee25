// OctoMap .bt / .ot bytes -> Scene::AddOctoMap, then a small point cloud inserted into the map
// (a copy of the tree, ray casting, leaf iteration).

#include "chasles/collision/scene.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  chasles::fuzz::Expect([&] {
    chasles::Scene scene;
    scene.AddOctoMap("map", bytes, Eigen::Isometry3d::Identity(), "scene.octomaps[0].data");
    chasles::PointCloudInsertion cloud;
    cloud.points = {0.5, 0.0, 0.2, -0.3, 0.4, 0.1};
    cloud.sensor_origin = Eigen::Vector3d(0.0, 0.0, 0.5);
    cloud.max_range = 2.0;
    chasles::PointCloudInsertionStats stats;
    scene.InsertPointCloud(cloud, &stats);
  });
  return 0;
}
