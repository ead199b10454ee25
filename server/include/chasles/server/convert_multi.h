#pragma once
/// \file
/// Conversion of the coordination and workcell messages (chasles.v1 Coordinate, CommitTrajectory,
/// Plan with a WorkcellContext). Internal to server/; errors name the proto field like convert.h.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "chasles/multi/coordinator.h"
#include "chasles/multi/moving_obstacles.h"
#include "chasles/planners/registry.h"
#include "chasles/server/model_store.h"
#include "chasles/server/workcells.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// The robot of a TeamRobot / CommitTrajectoryRequest (inline or by id), `field` naming it.
using TeamRobotResolver = std::function<std::shared_ptr<const RobotModel>(const v1::TeamRobot&, const std::string& field)>;

/// A CoordinateRequest with the proto's defaults (scene and robots resolved by the caller; the
/// workcell's committed motions are the caller's too). Also returns the request's time budget.
/// Start and goal values within `bounds_tolerance` outside a limit are clamped, each reported in
/// *warnings (robots[k].start.positions[i] …). More than `max_robots` robots (the server's
/// --max-team-robots) is INVALID_ARGUMENT, checked before any robot is resolved.
/// \throws Error(kInvalidArgument / kNotFound / kFailedPrecondition) naming the field.
CoordinationQuery CoordinationQueryFromProto(const v1::CoordinateRequest& request, std::shared_ptr<const Scene> scene,
                                             const TeamRobotResolver& resolve, const PlannerRegistry& registry,
                                             std::vector<std::string>* warnings, int max_robots = 1000);

/// A Plan request with a WorkcellContext or moving obstacles as a team of one (PRIORITIZED: its path, a roadmap and
/// the space-time search around the committed motions). Trajectory options beyond the velocity
/// and acceleration limits and the sample period are refused with INVALID_ARGUMENT. Start and
/// goal values within `bounds_tolerance` outside a limit are clamped, each reported in *warnings.
CoordinationQuery WorkcellPlanQuery(const v1::PlanRequest& request, std::shared_ptr<const RobotModel> robot,
                                    std::shared_ptr<const Scene> scene, const PlannerRegistry& registry,
                                    std::vector<std::string>* warnings);

v1::PlanOutcome CoordinationCodeToProto(CoordinationCode code);

/// PlanRequest.moving_obstacles in domain types (errors name `moving_obstacles[i]...`: no shapes,
/// no waypoints, times negative or not increasing, non-finite poses). At most `max_obstacles`.
/// \throws Error(kInvalidArgument).
std::vector<MovingObstacle> MovingObstaclesFromProto(const google::protobuf::RepeatedPtrField<v1::MovingObstacle>& obstacles,
                                                     int max_obstacles = 1000);


/// With `knots` (KnotsFor), each robot's trajectory also as knots (KnotsToProto).
void CoordinationOutcomeToProto(const CoordinationOutcome& outcome, const CoordinationQuery& query,
                                v1::CoordinateResponse* response, bool knots = false);

/// \throws Error(kInvalidArgument) for no robots or more than `max_robots` (--max-team-robots),
///         before any robot is resolved.
void CheckTeamSize(const v1::CoordinateRequest& request, int max_robots);

/// Teams larger than this get knots and no samples unless sample_period is set.
inline constexpr int kMaxTeamForSamplesByDefault = 16;
/// Whether a Coordinate response carries knots: knots_only, or a team of more than
/// kMaxTeamForSamplesByDefault robots.
bool KnotsFor(const v1::CoordinateRequest& request);

/// A team-of-one outcome as a PlanResponse (outcome, message, path, trajectory, duration).
void WorkcellPlanToProto(const CoordinationOutcome& outcome, const CoordinationQuery& query, v1::PlanResponse* response);

/// A JointTrajectory as sent back by Plan/Coordinate → the exact piecewise cubic Hermite
/// interpolant of its points' positions and velocities (linear when velocities are absent).
/// \throws Error(kInvalidArgument) naming `field.points[k]...`: no points, times not finite,
///         negative or not increasing, joint counts, non-finite values.
TimedTrajectory TrajectoryFromPoints(const v1::JointTrajectory& trajectory, const RobotModel& robot,
                                     const std::string& field);

/// A workcell-clock time field [s since the Unix epoch]: `value`, or `now` for 0.
/// \throws Error(kInvalidArgument) naming `field` when it is not finite or negative.
double ClockTimeFromProto(double value, double now, const std::string& field);

/// The reservation a CommitTrajectoryRequest asks for: the robot resolved (inline, by id — from
/// the shared store when this replica lacks it — or the default) and narrowed to `group`, the
/// trajectory rebuilt from its points, start_time resolved (0 = `now`), end_time and expires_at
/// filled in; `record` is the request as another replica rebuilds it (robot by id, start_time
/// resolved). \throws Error(kInvalidArgument) naming the field; Error(kNotFound) for an unknown
/// robot id.
Reservation ReservationFromCommit(const v1::CommitTrajectoryRequest& request, ModelStore& store, double now);

/// A reservation rebuilt from its record (ReservationFromCommit's), as WorkcellStore's loader.
Reservation ReservationFromRecord(const std::string& record, ModelStore& store);

}  // namespace chasles
