#pragma once
/// \file
/// MoveIt PlanningScene / MotionPlanRequest YAML -> chasles.v1 messages.
///
/// Reads moveit_msgs/PlanningScene and moveit_msgs/MotionPlanRequest written as YAML, in the
/// message field names (as Robowflex and MotionBenchMaker datasets store them: directories of
/// sceneNNNN.yaml / requestNNNN.yaml pairs). Points and quaternions may be maps ({x, y, z[, w]})
/// or sequences ([x, y, z], [x, y, z, w]); quaternions are always x, y, z, w. Primitive types and
/// object operations may be numbers (shape_msgs / moveit_msgs constants) or their names.
///
/// What converts (everything else that matters is a named error, never silently dropped):
/// - world.collision_objects[] with operation ADD (0, "add" or absent): BOX [x, y, z] (full
///   extents), SPHERE [radius], CYLINDER [height, radius] and inline meshes (triangles and
///   vertices, written as OBJ text). Each shape becomes one Chasles object named `<id>` when
///   the object has one shape, else `<id>/<k>` (k counts primitives, then meshes, from 0). Its
///   pose is frame ∘ object pose ∘ shape pose: the object pose (newer MoveIt; absent = identity),
///   the shape's entry of primitive_poses / mesh_poses, and the frame of header.frame_id, which
///   is the robot base for the robot's root link, "world", "/world" or "" (the MoveIt planning
///   frame is taken to coincide with the robot's root link), or a frame that
///   fixed_frame_transforms leads to from the base (chains followed).
/// - allowed_collision_matrix: a pair of names is allowed as MoveIt decides it (its entry if it
///   has one; else the default entries of the two names: one default decides, two must both
///   be true). Every allowed (robot link, object) pair becomes one LinkPair per shape of the
///   object; every allowed pair of robot links that the robot's own SRDF and adjacency do not
///   already allow becomes a link pair. Names that are neither robot links nor objects (e.g.
///   MoveIt's Panda finger links, absent from Chasles' Panda) are ignored.
/// - robot_state.joint_state (the start, overlaid by the request's start_state), joints not in
///   the robot (e.g. finger joints) ignored; multi_dof_joint_state ignored (Chasles robots have
///   no planar or floating joints).
/// - goal_constraints: exactly one entry, with joint constraints only. Robot joints without a
///   constraint keep their start position (as MoveIt keeps joints outside the planning group);
///   the tolerance is min(tolerance_above, tolerance_below) over the robot's constrained
///   joints, capped at 0.1 rad (0 or absent = Chasles' default 1e-3; the trajectory still ends
///   exactly at the goal positions).
/// - allowed_planning_time > 0 -> time_budget. planner_id, group_name, num_planning_attempts,
///   workspace_parameters and the velocity/acceleration scaling factors are not converted (the
///   caller chooses the planner and the trajectory options).
/// - world.octomap (octomap_msgs/OctomapWithPose): its tree (binary or full data, as int8
///   values) becomes the scene's OctoMap "octomap" at frame ∘ origin, the file built by
///   OctoMapFileFromMessage (header with the node count it walks).
/// - goal_constraints: one entry, either joint constraints (below) or one position and one
///   orientation constraint on the same link, which become a PoseGoal conservatively: position
///   tolerance = the largest ball about the region's centre inside its one SPHERE / BOX / CYLINDER
///   (at most 0.1 m), orientation tolerance = the least axis tolerance (at most 0.5 rad), so the
///   pose reached is inside MoveIt's region; target_point_offset must be 0.
/// - robot_state.attached_collision_objects (the scene's, then the request's start_state's; an
///   id given again replaces the scene's): each becomes one of the request's attached_objects —
///   BOX, SPHERE and CYLINDER primitives in the link's frame (an object given in another frame
///   is placed where the start puts that frame: a robot link by forward kinematics, the base or a
///   scene frame as above), touch links the robot lacks dropped. ImportPlanningScene alone refuses
///   them (a Scene cannot carry them).
/// Named errors: attached meshes, planes, cones, mesh resources, non-ADD operations,
/// OctoMaps other than OcTree or with corrupt data, visibility constraints, goal regions other than the above, path or trajectory
/// constraints, unknown frames, malformed YAML (with line and column) and malformed values.

#include <string>
#include <utility>
#include <vector>

#include "chasles/v1/chasles.pb.h"

namespace chasles::moveit {

/// The robot the YAML is read against.
struct RobotInfo {
  v1::RobotModel model;                  ///< inline description (UrdfRobot)
  std::vector<std::string> joint_names;  ///< the robot's non-fixed joints in configuration order
  std::vector<std::string> link_names;   ///< every link, root first
  std::string root_link;                 ///< the base frame of Chasles scenes
  /// Link pairs the robot never checks (SRDF disable_collisions and parent/child links), each
  /// as (smaller name, larger name), sorted. ACM entries for these pairs add nothing.
  std::vector<std::pair<std::string, std::string>> allowed_link_pairs;
};

/// The server's embedded default robot (examples/robots/panda.urdf and .srdf).
RobotInfo DefaultRobot();

/// A robot from URDF text and optional SRDF text (meshes are not supported here).
/// \throws Error(kInvalidArgument) naming the URDF/SRDF problem (field "robot.urdf...").
RobotInfo RobotFromUrdf(const std::string& urdf, const std::string& srdf);

/// A moveit_msgs/PlanningScene in YAML -> a Chasles scene in the robot's base frame.
/// `source` names the input in messages (e.g. the file name).
/// \throws Error(kInvalidArgument) `<source>: <key path> ...`, e.g.
///   `scene0003.yaml: world.collision_objects[2].primitives[0].type = 4 (CONE) is not supported
///   (BOX, SPHERE, CYLINDER and meshes are)`.
v1::Scene ImportPlanningScene(const std::string& yaml, const RobotInfo& robot, const std::string& source);

/// A PlanningScene and a moveit_msgs/MotionPlanRequest in YAML -> a PlanRequest with the scene
/// inline, start and goal in the robot's joint order, and time_budget from
/// allowed_planning_time. The robot and the planner are not set (the caller decides).
/// \throws Error(kInvalidArgument) naming the file and the key path, e.g.
///   `request0001.yaml: start_state.joint_state has no position for joint 'panda_joint3' (nor has
///   scene0001.yaml: robot_state.joint_state)`.
v1::PlanRequest ImportMotionPlanRequest(const std::string& scene_yaml, const std::string& request_yaml,
                                        const RobotInfo& robot, const std::string& scene_source,
                                        const std::string& request_source);

/// True when `request_yaml` is a moveit_msgs/GetCartesianPath request (it has `waypoints`).
bool IsCartesianPathRequest(const std::string& request_yaml);

/// A PlanningScene and a moveit_msgs/GetCartesianPath request in YAML -> a CartesianPathRequest
/// with the scene inline: start (as for a MotionPlanRequest), link_name -> link, waypoints
/// (geometry_msgs/Pose, in header.frame_id resolved as scene frames are) -> waypoints in the
/// base frame, max_step, jump_threshold (0 or >= 1), revolute_jump_threshold > 0 ->
/// max_joint_jump, avoid_collisions: false -> ignore_collisions (absent: collisions are checked,
/// unlike moveit_msgs' default). Named errors: prismatic_jump_threshold, path constraints,
/// max_cartesian_speed, an unknown link or frame, malformed values.
v1::CartesianPathRequest ImportCartesianPathRequest(const std::string& scene_yaml, const std::string& request_yaml,
                                                    const RobotInfo& robot, const std::string& scene_source,
                                                    const std::string& request_source);

/// One problem of a directory.
struct MoveItProblem {
  std::string name;         ///< the scene file's stem, e.g. "scene0001"
  v1::PlanRequest request;  ///< as ImportMotionPlanRequest returns it
};

/// Every sceneNNNN.yaml of `directory` with its requestNNNN.yaml (same digits), in numeric order
/// of NNNN. Other files (e.g. scene_sensed0001.yaml, README.md) are ignored.
/// \throws Error(kInvalidArgument) for an unreadable directory or file, a scene without its
///   request (or the reverse), no pairs at all, or any conversion error (naming the file).
std::vector<MoveItProblem> ImportProblemDirectory(const std::string& directory, const RobotInfo& robot);

/// A trajectory_msgs/JointTrajectory (or a moveit_msgs/RobotTrajectory holding one) in YAML or
/// JSON — what `chasles view --moveit-yaml / --ros-json` write, `ros2 topic echo` prints or
/// rosbridge sends — as the JointTrajectory an OptimizeRequest takes: joint names, positions
/// (and velocities, accelerations when given), time_from_start as {sec, nanosec}, {secs, nsecs}
/// or seconds. \throws Error(kInvalidArgument) naming `source` and the field (an empty list,
/// a point whose positions do not match joint_names, multi-DOF points).
v1::JointTrajectory ImportJointTrajectory(const std::string& text, const std::string& source);

}  // namespace chasles::moveit
