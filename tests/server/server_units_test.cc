// Unit tests of the server's pieces: content hash, LRU cache, worker pool, conversions, status map.
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "chasles/server/content_hash.h"
#include "chasles/server/convert.h"
#include "chasles/server/lru_cache.h"
#include "chasles/server/status.h"
#include "chasles/server/thread_pool.h"

namespace chasles {
namespace {

TEST(ContentHash, Sha256MatchesFips180Vectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // 56 bytes: the padding spills into a second block.
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  EXPECT_EQ(ContentId("abc"), "ba7816bf8f01cfea414140de5dae2223");
}

TEST(ContentHash, ProtoIdIsDeterministicAndDistinguishesTypes) {
  v1::UrdfRobot a;
  (*a.mutable_mesh_files())["x.stl"] = "1";
  (*a.mutable_mesh_files())["y.stl"] = "2";
  v1::UrdfRobot b;
  (*b.mutable_mesh_files())["y.stl"] = "2";
  (*b.mutable_mesh_files())["x.stl"] = "1";
  EXPECT_EQ(ProtoContentId(a), ProtoContentId(b));
  EXPECT_NE(ProtoContentId(v1::Scene()), ProtoContentId(v1::RobotModel()));
}

TEST(LruCache, EvictsTheLeastRecentlyUsedUntilTheBytesFit) {
  LruCache cache(100);  // bytes
  cache.Put<int>("a", std::make_shared<const int>(1), 40);
  cache.Put<int>("b", std::make_shared<const int>(2), 40);
  ASSERT_NE(cache.Get<int>("a"), nullptr);  // a is now the most recent
  cache.Put<int>("c", std::make_shared<const int>(3), 30);  // 110 > 100: b goes
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_EQ(cache.Get<int>("b"), nullptr);
  ASSERT_NE(cache.Get<int>("a"), nullptr);
  EXPECT_EQ(*cache.Get<int>("c"), 3);
  EXPECT_EQ(cache.stats().bytes, 70u);
  EXPECT_EQ(cache.stats().evictions, 1u);
  // Put keeps the first value stored under a key.
  EXPECT_EQ(*cache.Put<int>("c", std::make_shared<const int>(4), 30), 3);
  // One large entry evicts as many as it takes.
  cache.Put<int>("d", std::make_shared<const int>(5), 95);
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_EQ(cache.stats().bytes, 95u);
  // A value larger than the whole cache is handed back but not kept (nothing is evicted for it).
  const auto huge = cache.Put<int>("e", std::make_shared<const int>(6), 101);
  EXPECT_EQ(*huge, 6);
  EXPECT_EQ(cache.Get<int>("e"), nullptr);
  ASSERT_NE(cache.Get<int>("d"), nullptr);
  EXPECT_LE(cache.stats().bytes, cache.stats().capacity_bytes);
}

TEST(ThreadPool, RunsEveryJobAndRefusesBeyondItsQueue) {
  std::atomic<int> count{0};
  {
    ThreadPool pool(2);
    EXPECT_EQ(pool.num_threads(), 2);
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(pool.Submit([&] { count.fetch_add(1); }));
  }
  EXPECT_EQ(count.load(), 100);

  std::mutex gate;
  gate.lock();
  ThreadPool small(1, 1);
  ASSERT_TRUE(small.Submit([&] { std::lock_guard<std::mutex> hold(gate); }));
  // The worker may or may not have taken the first job yet; fill the queue until refused.
  int accepted = 0;
  while (small.Submit([] {}) && accepted < 3) ++accepted;
  EXPECT_LE(accepted, 1);
  gate.unlock();
}

TEST(Convert, PoseQuaternionRules) {
  v1::Pose pose;
  pose.mutable_position()->set_x(1.0);
  EXPECT_TRUE(PoseFromProto(pose, "p").linear().isIdentity());  // all-zero quaternion = identity
  EXPECT_DOUBLE_EQ(PoseFromProto(pose, "p").translation().x(), 1.0);

  pose.mutable_orientation()->set_w(2.0);
  try {
    PoseFromProto(pose, "scene.boxes[3].pose");
    FAIL() << "a quaternion of norm 2 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("scene.boxes[3].pose.orientation has norm 2"), std::string::npos) << e.what();
  }
  pose.mutable_orientation()->set_w(std::nan(""));
  EXPECT_THROW(PoseFromProto(pose, "p"), Error);
  pose.mutable_orientation()->set_w(1.0);
  pose.mutable_position()->set_z(std::numeric_limits<double>::infinity());
  try {
    PoseFromProto(pose, "q");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "q.position.z = inf must be finite");
  }
}

TEST(Convert, SceneNamesTheOffendingField) {
  v1::Scene scene;
  scene.add_boxes()->mutable_size()->set_x(1);
  scene.mutable_boxes(0)->mutable_size()->set_y(1);
  scene.mutable_boxes(0)->mutable_size()->set_z(1);
  scene.add_boxes()->mutable_size()->set_x(1);
  scene.mutable_boxes(1)->mutable_size()->set_y(1);
  scene.mutable_boxes(1)->mutable_size()->set_z(1);
  scene.add_boxes()->mutable_size()->set_x(-1);
  try {
    SceneFromProto(scene);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("scene.boxes[2].size.x = -1 must be"), std::string::npos) << e.what();
  }
  scene.mutable_boxes(2)->mutable_size()->set_x(1);
  scene.mutable_boxes(2)->mutable_size()->set_y(1);
  scene.mutable_boxes(2)->mutable_size()->set_z(1);
  auto parsed = SceneFromProto(scene);
  ASSERT_EQ(parsed->objects().size(), 3u);
  EXPECT_EQ(parsed->objects()[2].name, "box[2]");
}

TEST(Status, MapsEveryErrorAndNeverUnknown) {
  auto status_of = [](auto exception) { return StatusFromException(std::make_exception_ptr(exception)); };
  EXPECT_EQ(status_of(Error(ErrorCode::kInvalidArgument, "bad")).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status_of(Error(ErrorCode::kInvalidArgument, "bad")).error_message(), "bad");
  EXPECT_EQ(status_of(Error(ErrorCode::kNotFound, "x")).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(status_of(Error(ErrorCode::kFailedPrecondition, "x")).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  const grpc::Status internal = status_of(std::runtime_error("boom"));
  EXPECT_EQ(internal.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_NE(internal.error_message().find("boom"), std::string::npos);
  EXPECT_EQ(status_of(42).error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_EQ(StatusFromOutcome(PlanOutcomeCode::kCancelled, "").error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(StatusFromOutcome(PlanOutcomeCode::kDeadlineExceeded, "").error_code(),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  EXPECT_TRUE(StatusFromOutcome(PlanOutcomeCode::kNoPathWithinBudget, "").ok());
  EXPECT_TRUE(StatusFromOutcome(PlanOutcomeCode::kStartInCollision, "").ok());
}

}  // namespace
}  // namespace chasles
