#pragma once
/// \file
/// Fleet sessions (chasles.v1 OpenFleetSession, AssignFleetGoals, CloseFleetSession): lifelong
/// operation of a fleet of planar bases on multi/fleet_session.h, held in this server process.
/// Internal to server/; errors name the proto field like convert.h.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "chasles/multi/fleet_lattice.h"
#include "chasles/multi/fleet_session.h"
#include "chasles/planners/termination.h"
#include "chasles/server/convert_multi.h"
#include "chasles/server/redis_client.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// An open session: the planner and the names the wire uses. One goal batch at a time (mutex).
struct OpenFleet {
  std::mutex mutex;
  std::unique_ptr<FleetSession> session;
  std::vector<std::string> names;                   ///< robot names, by index
  std::vector<std::vector<std::string>> joint_names;  ///< per robot (its x, y, θ coordinates)
  std::map<std::string, int> index;                 ///< name -> index
  /// Shared store: the session's open record (which session of that name this is) and how many
  /// goal batches of its log the session holds.
  std::string record;
  std::uint64_t applied = 0;
};

/// Named sessions, at most `max_sessions` at once. Thread-safe.
///
/// With UseShared, sessions live in Redis too, so every replica serves every session: the open
/// request (robots and scene by id) under "chasles:fleet:<name>:open" and every goal batch, in
/// order, in the list "chasles:fleet:<name>:log" (the goals, those that failed with no
/// positions). A replica holds a local session and brings it up to date by replaying the batches
/// it has not applied (FleetSession is deterministic: a goal that succeeded there succeeds here
/// alike, one that failed is a Skip); a new batch is planned on a copy and appended with WATCH on
/// the log and MULTI/EXEC, so when another replica appended first it starts over from the newer
/// log, and two replicas never give out conflicting plans.
class FleetSessionStore {
 public:
  /// The session of an open record (OpenFleetFromProto with the server's collaborators).
  using Rebuild = std::function<std::shared_ptr<OpenFleet>(const v1::OpenFleetSessionRequest& record)>;

  explicit FleetSessionStore(std::size_t max_sessions = 64) : max_sessions_(max_sessions) {}
  /// Keeps sessions in Redis from now on (before serving).
  void UseShared(std::shared_ptr<RedisClient> redis, Rebuild rebuild);
  /// `record`: the request as another replica rebuilds the session (robots and scene by id,
  /// start_time resolved). \throws Error(kInvalidArgument) for a bad name,
  /// Error(kFailedPrecondition) when a session of that name is open, Error(kResourceExhausted) at the cap.
  void Add(const std::string& name, std::shared_ptr<OpenFleet> fleet, const v1::OpenFleetSessionRequest& record);
  /// \throws Error(kNotFound) naming the open sessions.
  std::shared_ptr<OpenFleet> Find(const std::string& name);
  /// Answers the request's goals on session `name` from `now` (AssignFleetGoalsFromProto).
  void Assign(const std::string& name, const v1::AssignFleetGoalsRequest& request, double now,
              const Termination& termination, v1::AssignFleetGoalsResponse* response);
  /// False when no such session was open.
  bool Close(const std::string& name);

 private:
  std::shared_ptr<OpenFleet> FindShared(const std::string& name);
  void AssignShared(const std::string& name, OpenFleet& fleet, const v1::AssignFleetGoalsRequest& request, double now,
                    const Termination& termination, v1::AssignFleetGoalsResponse* response);

  std::size_t max_sessions_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<OpenFleet>> sessions_;
  std::shared_ptr<RedisClient> redis_;
  Rebuild rebuild_;
};

/// The session an OpenFleetSessionRequest describes, its robots standing at their starts from
/// `start_time`; the lattice from `cache` under `scene_id`. Fills the response's lattice,
/// robots and warnings. \throws Error(kInvalidArgument) naming robots[k] and the field (not a
/// planar base, a base pose, a start off the lattice or on another robot's node, a limit, a
/// name), or more than `max_robots` robots.
std::shared_ptr<OpenFleet> OpenFleetFromProto(const v1::OpenFleetSessionRequest& request,
                                              std::shared_ptr<const Scene> scene, const std::string& scene_id,
                                              const TeamRobotResolver& resolve, double start_time, int max_robots,
                                              FleetLatticeCache* cache, v1::OpenFleetSessionResponse* response);

/// Applies a goal batch another replica appended to the shared log (FleetSessionStore):
/// goals with positions Assigned (they succeeded there, so they do here), the others Skipped.
/// \throws Error(kFailedPrecondition) for an unreadable batch or a replay that diverges.
void ReplayFleetGoals(OpenFleet& fleet, const std::string& batch);

/// Answers the request's goals on `fleet` (the caller holds fleet.mutex) from session time `now`.
/// \throws Error(kInvalidArgument) naming goals[k] (unknown robot, not 3 finite positions, off
///         the lattice or on a blocked node) or `now` before the session's start; goals before
///         the bad one are answered (and kept) only when none is bad: every goal is validated first.
void AssignFleetGoalsFromProto(OpenFleet& fleet, const v1::AssignFleetGoalsRequest& request, double now,
                               const Termination& termination, v1::AssignFleetGoalsResponse* response);

}  // namespace chasles
