// OctoMap input: valid .bt/.ot bytes load; corrupt, random, truncated and empty bytes fail with
// an Error naming the field, and never crash or hang.

#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/scene.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

const char kField[] = "scene.octomaps[0].data";

std::string SmallTreeBytes(bool binary) {
  octomap::OcTree tree(0.05);
  for (int i = 0; i < 20; ++i) tree.updateNode(octomap::point3d(0.05f * i + 0.025f, 0.125f, -0.175f), true);
  tree.updateNode(octomap::point3d(0.325f, 0.325f, 0.325f), false);
  std::stringstream s;
  if (binary) tree.writeBinary(s);
  else tree.write(s);
  return s.str();
}

// Returns the error message, or "" when AddOctoMap accepted the bytes.
std::string AddError(const std::string& bytes) {
  Scene scene;
  try {
    scene.AddOctoMap("map", bytes, Eigen::Isometry3d::Identity(), kField);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find(kField), std::string::npos) << e.what();
    return e.what();
  }
  EXPECT_EQ(scene.occupancy_maps().size(), 1u);
  return "";
}

TEST(OctoMapInput, BinaryAndFullFormatsLoad) {
  for (bool binary : {true, false}) {
    Scene scene;
    scene.AddOctoMap("map", SmallTreeBytes(binary), Eigen::Isometry3d::Identity(), kField);
    ASSERT_EQ(scene.occupancy_maps().size(), 1u);
    const auto& tree = *scene.occupancy_maps()[0].tree;
    EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
    const octomap::OcTreeNode* hit = tree.search(0.525, 0.125, -0.175);
    ASSERT_NE(hit, nullptr);
    EXPECT_TRUE(tree.isNodeOccupied(hit));
  }
}

TEST(OctoMapInput, ExampleShelfMapLoadsAndCoversTheShelf) {
  auto octo = test::LoadScene("scenes/shelf_octomap.json");
  ASSERT_EQ(octo->occupancy_maps().size(), 1u);
  const auto& tree = *octo->occupancy_maps()[0].tree;
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.02);
  // Every point sampled inside a shelf box lies in an occupied voxel.
  auto shelf = test::LoadScene("scenes/shelf.json");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (const SceneObject& o : shelf->objects()) {
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d local(u(rng) * o.shape.size.x(), u(rng) * o.shape.size.y(), u(rng) * o.shape.size.z());
      const Eigen::Vector3d p = o.shape.pose * local;
      const octomap::OcTreeNode* node = tree.search(p.x(), p.y(), p.z());
      ASSERT_NE(node, nullptr) << o.name << " at " << p.transpose();
      EXPECT_TRUE(tree.isNodeOccupied(node)) << o.name;
    }
  }
  // And a point well away from the shelf is not occupied.
  const octomap::OcTreeNode* free_node = tree.search(0.3, 0.0, 0.5);
  EXPECT_TRUE(free_node == nullptr || !tree.isNodeOccupied(free_node));
}

TEST(OctoMapInput, EmptyBytes) { EXPECT_NE(AddError("").find("is empty"), std::string::npos); }

TEST(OctoMapInput, NotAnOctoMap) {
  const std::string e = AddError("solid cube\nfacet normal 0 0 1\n");
  EXPECT_NE(e.find("is not an OctoMap file (expected a '# Octomap OcTree' header)"), std::string::npos) << e;
}

TEST(OctoMapInput, RandomBytesNeverCrash) {
  std::mt19937_64 rng(1234);
  for (int trial = 0; trial < 200; ++trial) {
    std::string bytes(1 + rng() % 2000, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    EXPECT_NE(AddError(bytes), "");
  }
}

TEST(OctoMapInput, RandomDataAfterAValidHeaderNeverCrashes) {
  std::mt19937_64 rng(99);
  const std::string headers[] = {"# Octomap OcTree binary file\nid OcTree\nsize 100\nres 0.05\ndata\n",
                                 "# Octomap OcTree file\nid OcTree\nsize 100\nres 0.05\ndata\n"};
  int accepted = 0;
  for (const std::string& h : headers) {
    for (int trial = 0; trial < 300; ++trial) {
      std::string bytes = h;
      const std::size_t n = rng() % 600;
      for (std::size_t i = 0; i < n; ++i) bytes.push_back(static_cast<char>(rng()));
      if (AddError(bytes).empty()) ++accepted;  // a random stream may happen to be a valid tree
    }
  }
  SUCCEED() << accepted << " random streams happened to be valid trees";
}

TEST(OctoMapInput, TruncatedFilesAreNamed) {
  for (bool binary : {true, false}) {
    const std::string bytes = SmallTreeBytes(binary);
    const std::size_t data = bytes.find("data\n") + 5;
    for (std::size_t cut : {data + 1, data + 3, bytes.size() - 1, bytes.size() / 2, data - 2, std::size_t{10}}) {
      const std::string e = AddError(bytes.substr(0, cut));
      EXPECT_NE(e, "") << "cut at " << cut;
    }
  }
  const std::string shelf = test::ReadFile(test::ExamplePath("scenes/shelf.bt"));
  EXPECT_NE(AddError(shelf.substr(0, shelf.size() - 7)).find("truncated or corrupt"), std::string::npos);
}

TEST(OctoMapInput, CorruptHeaderFields) {
  EXPECT_NE(AddError("# Octomap OcTree binary file\nid ColorOcTree\nsize 1\nres 0.1\ndata\n\x01\x00")
                .find("only 'OcTree'"),
            std::string::npos);
  EXPECT_NE(AddError("# Octomap OcTree binary file\nid OcTree\nsize 1\nres -1\ndata\n\x01\x00").find("res"),
            std::string::npos);
  EXPECT_NE(AddError("# Octomap OcTree binary file\nid OcTree\nsize 0\nres 0.1\ndata\n").find("empty"),
            std::string::npos);
  EXPECT_NE(AddError("# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\n").find("header"),
            std::string::npos);
  // All-zero children: a tree with no leaves.
  EXPECT_NE(AddError(std::string("# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\ndata\n") +
                     std::string(2, '\0'))
                .find("empty"),
            std::string::npos);
  // Every child "has children" forever: deeper than 16 levels.
  EXPECT_NE(AddError(std::string("# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\ndata\n") +
                     std::string(4096, '\xff'))
                .find("truncated or corrupt"),
            std::string::npos);
}

}  // namespace
}  // namespace chasles
