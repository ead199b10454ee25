#pragma once
/// \file
/// Conversion between the wire types (chasles.v1) and the domain types. Internal to server/.
/// Every function validates its input and throws Error(kInvalidArgument) naming the proto field
/// path, index, value and rule, e.g. `scene.boxes[2].size.x = -1 must be > 0`.

#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "chasles/collision/scene.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/robot/robot_model.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// The id of a message: ContentId of its deterministic serialization (map keys sorted).
std::string ProtoContentId(const google::protobuf::Message& message);

/// Pose → isometry. An all-zero quaternion is identity; others must have norm 1 (±1e-3, then
/// normalised); every number must be finite.
Eigen::Isometry3d PoseFromProto(const v1::Pose& pose, const std::string& field);

/// Parses a robot: every mesh file through ParseMesh, then RobotModel::FromUrdf.
std::shared_ptr<const RobotModel> RobotFromProto(const v1::RobotModel& robot,
                                                 const std::string& field = "robot");

/// Builds a scene from primitives, meshes and OctoMaps. Unnamed objects are called e.g. `box[2]`.
std::shared_ptr<const Scene> SceneFromProto(const v1::Scene& scene, const std::string& field = "scene");

/// Request settings that are not part of PlanQuery.
struct RequestSettings {
  double time_budget = 5.0;  ///< [s], in (0, 600]
};

/// The query part of a request (start, goal, planner, trajectory options, seed, resolution),
/// with every default applied as documented in the proto. `checker` supplies the robot.
/// \throws Error(kInvalidArgument) naming the field, Error(kNotFound) for an unknown planner.
PlanQuery PlanQueryFromProto(const v1::PlanRequest& request,
                             std::shared_ptr<const CollisionChecker> checker,
                             const PlannerRegistry& registry, RequestSettings* settings);

/// The wire outcome of a domain outcome (kCancelled/kDeadlineExceeded have none: they are
/// gRPC statuses; they map to PLAN_OUTCOME_UNSPECIFIED here).
v1::PlanOutcome OutcomeToProto(PlanOutcomeCode code);

/// Fills outcome, message, path, trajectory, duration, timings, statistics and verification.
void PlanOutcomeToProto(const PlanOutcome& outcome, const PlanQuery& query, v1::PlanResponse* response);

/// Fills a catalogue entry.
void PlannerSpecToProto(const PlannerSpec& spec, v1::PlannerDescription* description);


}  // namespace chasles
