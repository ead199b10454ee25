#pragma once
/// \file
/// Conversion between the wire types (chasles.v1) and the domain types. Internal to server/.
/// Every function validates its input and throws Error(kInvalidArgument) naming the proto field
/// path, index, value and rule, e.g. `scene.boxes[2].size.x = -1 must be > 0`.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/collision/scene.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/robot/attached_objects.h"
#include "chasles/robot/descriptions.h"
#include "chasles/robot/input_limits.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/robot/robot_model.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// The id of a message: ContentId of its deterministic serialization (map keys sorted).
std::string ProtoContentId(const google::protobuf::Message& message);

/// Pose → isometry. An all-zero quaternion is identity; others must have norm 1 (±1e-3, then
/// normalised); every number must be finite.
Eigen::Isometry3d PoseFromProto(const v1::Pose& pose, const std::string& field);
/// The reverse (unit quaternion with w >= 0, for stable output).
void PoseToProto(const Eigen::Isometry3d& pose, v1::Pose* out);
/// Appends the values (joint positions, velocities) to `out`.
void ToProto(const Eigen::VectorXd& values, google::protobuf::RepeatedField<double>* out);
/// One value per joint of `robot`, each finite: errors name `field` (`velocities has 2 values,
/// robot 'x' has 3 joints`, `velocities[1] = nan must be finite`). No limits are checked.
Eigen::VectorXd JointValuesFromProto(const google::protobuf::RepeatedField<double>& values, const RobotModel& robot,
                                     const std::string& field);
/// A unit quaternion (norm 1 within 1e-3, normalised); all zero = identity.
/// \throws Error(kInvalidArgument) naming `field` (and .x/.y/.z/.w).
Eigen::Quaterniond QuaternionFromProto(const v1::Quaternion& q, const std::string& field);
/// Path constraints on `robot`, links by name (empty = "tool", else the last link).
/// \throws Error(kInvalidArgument) naming `field`.orientation[i] / .position[i] and the rule.
std::shared_ptr<const PathConstraints> PathConstraintsFromProto(const v1::PathConstraints& constraints,
                                                                std::shared_ptr<const RobotModel> robot,
                                                                const std::string& field);

/// Parses a robot: URDF (every mesh file through ParseMesh, then RobotModel::FromUrdf), a DH
/// table (RobotFromDh) or a PoE screw list (RobotFromPoe). Errors name the proto field, e.g.
/// `robot.dh.joints[2].alpha = nan must be finite`, `robot.poe.joints[1].screw: ...`.
/// `limits` caps the URDF/SRDF text, each mesh file and the robot's size (Error(kResourceExhausted)).
std::shared_ptr<const RobotModel> RobotFromProto(const v1::RobotModel& robot,
                                                 const std::string& field = "robot",
                                                 const InputLimits& limits = {});

/// DhRobot → DhDescription (numbers checked finite, shapes checked positive); `field` is the
/// path of the DhRobot, e.g. "robot.dh". Limits and the table itself are checked by RobotFromDh.
DhDescription DhFromProto(const v1::DhRobot& dh, const std::string& field);
/// PoeRobot → PoeDescription; `field` e.g. "robot.poe".
PoeDescription PoeFromProto(const v1::PoeRobot& poe, const std::string& field);

/// The link named `name` (empty = "tool" if the robot has one, else the last link).
/// \throws Error(kInvalidArgument) naming `field`, the link and the known links.
int LinkFromProto(const RobotModel& robot, const std::string& name, const std::string& field);

/// An InverseKinematicsRequest's solver settings with the proto's defaults and ranges applied
/// (robot/scene resolution and `accept` are the caller's). \throws Error(kInvalidArgument).
IkRequest IkRequestFromProto(const v1::InverseKinematicsRequest& request, const RobotModel& robot);

/// Fills solved, message, joint_names, solutions, manipulability, singular (the Jacobian of
/// `ik.link` at each solution), best errors, attempts and seconds.
void IkResultToProto(const IkResult& result, const IkRequest& ik, const RobotModel& robot,
                     v1::InverseKinematicsResponse* response);

/// Builds a scene from primitives, meshes and OctoMaps. Unnamed objects are called e.g. `box[2]`.
/// `limits` caps each mesh and OctoMap (Error(kResourceExhausted)).
std::shared_ptr<const Scene> SceneFromProto(const v1::Scene& scene, const std::string& field = "scene",
                                            const InputLimits& limits = {});

/// The point cloud of an UpdateScene request (its values are checked by Scene::InsertPointCloud).
PointCloudInsertion PointCloudInsertionFromProto(const v1::UpdateSceneRequest& request);

/// A PoseGoal with the proto's defaults and ranges; `field` names it, e.g. "robots[1].pose_goal".
PoseGoalSpec PoseGoalFromProto(const v1::PoseGoal& goal, const RobotModel& robot, const std::string& field);

/// Planner parameters typed against `spec` (bool vs number) and resolved (ranges, defaults);
/// `field` names the PlannerConfig, e.g. "planner".
ParameterValues PlannerParametersFromProto(const v1::PlannerConfig& config, const PlannerSpec& spec,
                                           const std::string& field);

/// Joint positions: count, finiteness and joint limits checked, errors naming `field`. With
/// `warnings`, values at most `bounds_tolerance` outside a limit are first clamped onto it, each
/// reported there (ClampOntoLimits).
Eigen::VectorXd ConfigurationFromProto(const google::protobuf::RepeatedField<double>& values, const RobotModel& robot,
                                       const std::string& field, double bounds_tolerance = 0.0,
                                       std::vector<std::string>* warnings = nullptr);

/// Samples → JointTrajectory points (joint names from `robot`).
void SamplesToProto(const std::vector<TrajectorySample>& samples, const RobotModel& robot,
                    v1::JointTrajectory* trajectory);

/// Request settings that are not part of PlanQuery.
struct RequestSettings {
  double time_budget = 5.0;  ///< [s], in (0, 600]
  /// What the conversion adjusted, one sentence each (start/goal values clamped onto a limit).
  std::vector<std::string> warnings;
};

/// A robot's load warnings as the proto names them: the loader's "srdf: …" become
/// "<field>.urdf.srdf: …".
std::vector<std::string> RobotWarnings(const RobotModel& robot, const std::string& field);

/// PlanRequest.bounds_tolerance's default [rad or m].
inline constexpr double kDefaultBoundsTolerance = 1e-6;

/// PlanRequest.bounds_tolerance with its default: 0 = kDefaultBoundsTolerance.
/// \throws Error(kInvalidArgument) `bounds_tolerance = 0.02 must be within [0, 0.01]`.
double BoundsToleranceFromProto(double value);

/// Values of q at most `tolerance` outside a joint limit are set onto it, each reported in
/// *warnings naming `field`, the index, the value, the limit and the joint. A continuous joint's
/// value farther out is wrapped by a multiple of 2π into its planning range [-π, π] (reported
/// too). Other values farther out (and NaN) are left for RobotModel::ValidateConfiguration to refuse.
void ClampOntoLimits(const RobotModel& robot, double tolerance, const std::string& field, Eigen::VectorXd* q,
                     std::vector<std::string>* warnings);

/// A request's safety margin around every robot shape [m] (PlanRequest/OptimizeRequest
/// `padding`; 0 = none): the value, checked to be in [0, 0.5].
/// \throws Error(kInvalidArgument) e.g. `padding = -1 must be in [0, 0.5] m`.
double PaddingFromProto(double padding, const std::string& field);

/// The query part of a request (start, joint or pose goal, gravity, planner, trajectory options, seed, resolution),
/// with every default applied as documented in the proto. `checker` supplies the robot.
/// \throws Error(kInvalidArgument) naming the field, Error(kNotFound) for an unknown planner.
PlanQuery PlanQueryFromProto(const v1::PlanRequest& request,
                             std::shared_ptr<const CollisionChecker> checker,
                             const PlannerRegistry& registry, RequestSettings* settings);

/// The wire outcome of a domain outcome (kCancelled/kDeadlineExceeded have none: they are
/// gRPC statuses; they map to PLAN_OUTCOME_UNSPECIFIED here).
v1::PlanOutcome OutcomeToProto(PlanOutcomeCode code);

/// Fills outcome, message, path, trajectory (with efforts when computed), duration, timings,
/// statistics, verification and, for a pose goal, reached_goal and goal_manipulability; with
/// `knots`, also the trajectory's knots (KnotsToProto).
void PlanOutcomeToProto(const PlanOutcome& outcome, const PlanQuery& query, v1::PlanResponse* response,
                        bool knots = false);

/// The trajectory as TrajectoryKnots (one knot per piece start, and the end): exact for pieces
/// of degree <= 2 (constant acceleration between knots). False, and *out left empty, when a
/// piece has a higher degree.
bool KnotsToProto(const TimedTrajectory& trajectory, const std::vector<std::string>& joint_names,
                  v1::TrajectoryKnots* out);

/// Trajectory options (limits, post-processing and its options) with the proto's defaults;
/// `field` prefixes the names in errors ("trajectory" in PlanRequest, "options" in
/// OptimizeRequest). \throws Error(kInvalidArgument) naming the field, index, value and rule.
TrajectorySpec TrajectorySpecFromProto(const v1::TrajectoryOptions& options, const RobotModel& robot,
                                       const std::string& field);

/// The Optimize query: path (or a timed trajectory's positions, with its duration in
/// `input_duration` and its boundary velocities when start/end_velocity are not given),
/// options, gravity, resolution, budget (`settings`). \throws Error(kInvalidArgument) naming the field.
OptimizeQuery OptimizeQueryFromProto(const v1::OptimizeRequest& request, std::shared_ptr<const CollisionChecker> checker,
                                     RequestSettings* settings, double* input_duration);

/// Fills outcome, message, timings, verification, optimizer and (on success) quality,
/// trajectory, duration and, with `knots`, the knots.
void OptimizeOutcomeToProto(const OptimizeOutcome& outcome, const OptimizeQuery& query, v1::OptimizeResponse* response,
                            bool knots = false);

/// Attached objects in domain types: link names resolved, shapes converted (errors name
/// `field[i]...`). \throws Error(kInvalidArgument).
std::vector<AttachedObject> AttachedObjectsFromProto(const google::protobuf::RepeatedPtrField<v1::AttachedObject>& objects,
                                                     const RobotModel& robot, const std::string& field);

/// A moving obstacle's primitives (errors name `field.boxes[i]...`). \throws Error(kInvalidArgument).
std::vector<Shape> MovingObstacleShapesFromProto(const v1::MovingObstacle& obstacle, const std::string& field);

/// Fills a catalogue entry.
void PlannerSpecToProto(const PlannerSpec& spec, v1::PlannerDescription* description);


}  // namespace chasles
