// STL (ASCII or binary) or OBJ bytes -> ParseMesh, then the mesh as a scene object.

#include "chasles/collision/mesh.h"
#include "chasles/collision/scene.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  chasles::fuzz::Expect([&] {
    chasles::Shape shape;
    shape.type = chasles::ShapeType::kMesh;
    shape.mesh = chasles::ParseMesh(bytes, Eigen::Vector3d(1.0, 2.0, 0.5), "scene.meshes[0].data");
    chasles::Scene scene;
    scene.AddObject({"mesh", shape}, "scene.meshes[0]");
  });
  return 0;
}
