"""Results of Plan, Optimize, CartesianPath, ListPlanners and UploadRobot as dataclasses with numpy arrays."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

import numpy as np

from ._stubs import pb
from .convert import message_to_dict, outcome_name
from .trajectory import Trajectory


@dataclass
class RobotInfo:
    """What UploadRobot answered about a robot: its joints and limits.

    Attributes:
        robot_id: the content hash to use as ``robot_id``.
        joint_names: the n joint names in the robot's joint order.
        lower_limits, upper_limits: position limits, shape (n,) [rad] or [m].
        velocity_limits: shape (n,) [rad/s] or [m/s].
        warnings: what the server skipped while reading the description (e.g. SRDF pairs naming
            links the URDF lacks), one sentence each.
        collision_model: how its collision geometry is checked: ``{"kind": "shapes"}``, or for a
            robot with meshes ``{"kind": "fitted_spheres", "spheres": …, "shapes_fitted": …,
            "reach": … [m], "reach_link": …, "fit_seconds": …}``.
        groups: the SRDF's planning groups, name → joint names (plan with ``group=name``).
    """

    robot_id: str
    joint_names: List[str]
    lower_limits: np.ndarray
    upper_limits: np.ndarray
    velocity_limits: np.ndarray
    warnings: List[str] = field(default_factory=list)
    collision_model: Dict[str, Any] = field(default_factory=dict)
    groups: Dict[str, List[str]] = field(default_factory=dict)

    @classmethod
    def from_response(cls, response: pb.UploadRobotResponse) -> "RobotInfo":
        c = response.collision_model
        collision = {"kind": c.kind}
        if c.kind == "fitted_spheres":
            collision.update(spheres=c.spheres, shapes_fitted=c.shapes_fitted, reach=c.reach,
                             reach_link=c.reach_link, fit_seconds=c.fit_seconds)
        return cls(robot_id=response.robot_id, joint_names=list(response.joint_names),
                   lower_limits=np.array(response.lower_limits, dtype=float),
                   upper_limits=np.array(response.upper_limits, dtype=float),
                   velocity_limits=np.array(response.velocity_limits, dtype=float),
                   warnings=list(response.warnings), collision_model=collision,
                   groups={g.name: list(g.joint_names) for g in response.groups})


@dataclass
class ParameterInfo:
    """One typed planner parameter (ListPlanners)."""

    name: str
    description: str
    type: str  # "double", "int" or "bool"
    default: float
    min: float
    max: float
    per_joint: bool


@dataclass
class PlannerInfo:
    """One planner of the server's catalogue (ListPlanners)."""

    id: str
    description: str
    optimizing: bool
    robot_kinds: List[str]
    parameters: List[ParameterInfo]

    @classmethod
    def from_message(cls, message: pb.PlannerDescription) -> "PlannerInfo":
        return cls(
            id=message.id, description=message.description, optimizing=message.optimizing,
            robot_kinds=list(message.robot_kinds),
            parameters=[ParameterInfo(name=p.name, description=p.description,
                                      type=pb.ParameterDescription.Type.Name(p.type).lower(),
                                      default=p.default_value, min=p.min, max=p.max, per_joint=p.per_joint)
                        for p in message.parameters])


def limits_used(options: Optional[pb.TrajectoryOptions],
                model_velocity: Optional[np.ndarray]) -> "tuple[Optional[np.ndarray], Optional[np.ndarray]]":
    """The (velocity, acceleration) limits the server applies, as far as the client knows them.

    As on the server: the velocity limits are the request's ``max_velocity`` capped at the model's
    (or the model's when none are given); the acceleration limits are the request's
    ``max_acceleration``, else twice the velocity limits. ``model_velocity`` None = unknown (then a
    requested ``max_velocity`` is returned uncapped).
    """
    velocity: Optional[np.ndarray] = None
    acceleration: Optional[np.ndarray] = None
    if options is not None and len(options.max_velocity) > 0:
        velocity = np.array(options.max_velocity, dtype=float)
        if model_velocity is not None and model_velocity.shape == velocity.shape:
            velocity = np.minimum(velocity, model_velocity)
    elif model_velocity is not None:
        velocity = np.array(model_velocity, dtype=float)
    if options is not None and len(options.max_acceleration) > 0:
        acceleration = np.array(options.max_acceleration, dtype=float)
    elif velocity is not None:
        acceleration = 2.0 * velocity
    return velocity, acceleration


def _path_array(states: Any, dof: int) -> np.ndarray:
    if len(states) == 0:
        return np.zeros((0, dof))
    return np.array([list(s.positions) for s in states], dtype=float)


def _limits_of(response: Any, velocity: Optional[np.ndarray], acceleration: Optional[np.ndarray]):
    """The limits the response reports (TrajectoryLimits), else the client's own reckoning."""
    if response.HasField("limits") and len(response.limits.max_velocity) > 0:
        return (np.array(response.limits.max_velocity, dtype=float),
                np.array(response.limits.max_acceleration, dtype=float))
    return velocity, acceleration


def _common_fields(response: Any, velocity: Optional[np.ndarray], acceleration: Optional[np.ndarray]) -> Dict[str, Any]:
    """The fields PlanResult and OptimizeResult read alike from their responses."""
    velocity, acceleration = _limits_of(response, velocity, acceleration)
    return dict(
        outcome=outcome_name(response.outcome), message=response.message, success=response.outcome == pb.SUCCESS,
        request_id=response.request_id,
        trajectory=Trajectory.from_response(response) if len(response.trajectory.points) > 0 else None,
        duration=response.duration, timings=message_to_dict(response.timings),
        verification=message_to_dict(response.verification), quality=message_to_dict(response.quality),
        optimizer=message_to_dict(response.optimizer), robot_id=response.robot_id, scene_id=response.scene_id,
        velocity_limits=velocity, acceleration_limits=acceleration, response=response)


@dataclass
class PlanResult:
    """The answer to a Plan request.

    Attributes:
        outcome: the PlanOutcome name, e.g. ``"SUCCESS"``, ``"NO_PATH_WITHIN_BUDGET"``.
        message: the server's reason or summary.
        success: ``outcome == "SUCCESS"`` (a verified trajectory is present).
        trajectory: the timed trajectory (None unless success).
        path: the shortened geometric path, shape (M, n) [rad] (start … goal).
        duration: trajectory duration [s].
        timings, statistics, verification, quality, optimizer: the response's StageTimings,
            PlannerStatistics, Verification, TrajectoryQuality and OptimizerStatistics as dicts
            with snake_case keys (units as in the proto).
        velocity_limits, acceleration_limits: the limits the trajectory was timed with, shape (n,):
            the response's ``limits`` (TrajectoryLimits); from a server that sends none, the
            client's own reckoning when it knows the model (see ``limits_used``); else None.
        reached_goal: for a pose goal, the IK solution reached (else None).
        warnings: what the server adjusted or skipped (start/goal values clamped onto a limit
            within ``bounds_tolerance``, an inline robot's SRDF pairs skipped), one sentence each.
        repair: when the first trajectory failed dense verification, the response's
            VerificationRepair as a dict (``failure``, ``actions`` — each repair tried with its
            result — and ``repaired``); None when the first trajectory passed.
        response: the raw chasles.v1.PlanResponse.
    """

    outcome: str
    message: str
    success: bool
    request_id: str
    trajectory: Optional[Trajectory]
    path: np.ndarray
    duration: float
    timings: Dict[str, float]
    statistics: Dict[str, Any]
    verification: Dict[str, Any]
    quality: Dict[str, Any]
    optimizer: Dict[str, Any]
    robot_id: str
    scene_id: str
    reached_goal: Optional[np.ndarray] = None
    goal_manipulability: float = 0.0
    velocity_limits: Optional[np.ndarray] = None
    acceleration_limits: Optional[np.ndarray] = None
    warnings: List[str] = field(default_factory=list)
    repair: Optional[Dict[str, Any]] = None
    response: pb.PlanResponse = field(default_factory=pb.PlanResponse, repr=False)
    request: Optional[pb.PlanRequest] = field(default=None, repr=False)  # set by Client.plan / plan_request

    def save_html(self, path: Any) -> Any:
        """Writes the 3-D viewer page (self-contained; opens offline) of this plan: the robot moving
        through the scene, its trail, waypoints, limit plots and closest approach. Returns the path."""
        from .view import write_view  # noqa: PLC0415
        return write_view(self.response, self.request, path)

    def show(self) -> Any:
        """The viewer page inline in a notebook, else opened in the browser."""
        from .view import show_view  # noqa: PLC0415
        return show_view(self.response, self.request)

    @classmethod
    def from_response(cls, response: pb.PlanResponse, velocity_limits: Optional[np.ndarray] = None,
                      acceleration_limits: Optional[np.ndarray] = None) -> "PlanResult":
        common = _common_fields(response, velocity_limits, acceleration_limits)
        trajectory = common["trajectory"]
        dof = trajectory.dof if trajectory is not None else (len(response.path[0].positions) if response.path else 0)
        return cls(
            **common, path=_path_array(response.path, dof), statistics=message_to_dict(response.statistics),
            reached_goal=(np.array(response.reached_goal.positions, dtype=float)
                          if len(response.reached_goal.positions) > 0 else None),
            goal_manipulability=response.goal_manipulability, warnings=list(response.warnings),
            repair=message_to_dict(response.repair) if response.HasField("repair") else None)


@dataclass
class ReplanResult:
    """One answer of a replanning stream (``Client.replan``).

    Attributes:
        sequence: the message answered (0 = the first).
        action: ``"PLANNED"`` (the first message or a new problem), ``"KEPT"`` (the current
            trajectory still holds: its rest from ``time``) or ``"REPLANNED"`` (see ``reason``).
        reason: what invalidated the current trajectory (empty unless replanned).
        time: [s] the stream's clock at the trajectory's t = 0.
        plan: the trajectory from the robot's state, as ``Client.plan`` returns it.
        seconds: [s] the server's time on this answer.
    """

    sequence: int
    action: str
    reason: str
    time: float
    plan: PlanResult
    seconds: float

    @classmethod
    def from_response(cls, response: Any) -> "ReplanResult":
        return cls(sequence=response.sequence, action=type(response).Action.Name(response.action),
                   reason=response.reason, time=response.time, plan=PlanResult.from_response(response.plan),
                   seconds=response.seconds)


@dataclass
class OptimizeResult:
    """The answer to an Optimize request (fields as in ``PlanResult``).

    Attributes:
        input_duration: duration of the input trajectory [s]; 0 for a path.
    """

    outcome: str
    message: str
    success: bool
    request_id: str
    trajectory: Optional[Trajectory]
    duration: float
    input_duration: float
    timings: Dict[str, float]
    verification: Dict[str, Any]
    quality: Dict[str, Any]
    optimizer: Dict[str, Any]
    robot_id: str
    scene_id: str
    velocity_limits: Optional[np.ndarray] = None
    acceleration_limits: Optional[np.ndarray] = None
    response: pb.OptimizeResponse = field(default_factory=pb.OptimizeResponse, repr=False)
    request: Optional[pb.OptimizeRequest] = field(default=None, repr=False)  # set by Client.optimize

    def save_html(self, path: Any) -> Any:
        """Writes the 3-D viewer page of this optimised trajectory (see PlanResult.save_html)."""
        from .view import write_view  # noqa: PLC0415
        return write_view(self.response, self.request, path)

    def show(self) -> Any:
        """The viewer page inline in a notebook, else opened in the browser."""
        from .view import show_view  # noqa: PLC0415
        return show_view(self.response, self.request)

    @classmethod
    def from_response(cls, response: pb.OptimizeResponse, velocity_limits: Optional[np.ndarray] = None,
                      acceleration_limits: Optional[np.ndarray] = None) -> "OptimizeResult":
        return cls(**_common_fields(response, velocity_limits, acceleration_limits),
                   input_duration=response.input_duration)


@dataclass
class CartesianResult:
    """The answer to a CartesianPath request.

    Attributes:
        stop: why the path ended: ``"COMPLETE"``, ``"UNREACHABLE"``, ``"JOINT_JUMP"``,
            ``"RELATIVE_JUMP"``, ``"COLLISION"``, ``"START_INVALID"`` or ``"CANCELLED"``.
        message: where and why it ended (empty when complete).
        fraction: steps achieved / steps of the whole move, in [0, 1] (MoveIt's fraction).
        complete: ``stop == "COMPLETE"``.
        success: complete and timed (``timed.success``).
        path: the states achieved, shape (M, n) [rad], start first.
        steps, waypoints_reached: of the whole move.
        max_position_error, max_orientation_error: the states' poses from their targets [m], [rad].
        max_line_deviation: [m] the link from the line between states (measured at 7 points a step).
        trajectory_line_deviation: [m] the link from the lines over the timed trajectory.
        timed: the states timed as ``Client.optimize`` would (None with fewer than two states).
        warnings: what the server adjusted (e.g. attached objects covered by spheres).
    """

    stop: str
    message: str
    fraction: float
    complete: bool
    success: bool
    path: np.ndarray
    joint_names: List[str]
    steps: int
    waypoints_reached: int
    max_position_error: float
    max_orientation_error: float
    max_line_deviation: float
    trajectory_line_deviation: float
    timed: Optional[OptimizeResult]
    warnings: List[str]
    request_id: str
    robot_id: str
    scene_id: str
    response: pb.CartesianPathResponse = field(default_factory=pb.CartesianPathResponse, repr=False)

    @property
    def trajectory(self) -> Optional[Trajectory]:
        """The timed trajectory (None unless timed successfully)."""
        return self.timed.trajectory if self.timed is not None else None

    @classmethod
    def from_response(cls, response: pb.CartesianPathResponse, velocity_limits: Optional[np.ndarray] = None,
                      acceleration_limits: Optional[np.ndarray] = None) -> "CartesianResult":
        stop = pb.CartesianPathResponse.Stop.Name(response.stop)
        timed = (OptimizeResult.from_response(response.timed, velocity_limits, acceleration_limits)
                 if response.HasField("timed") else None)
        return cls(stop=stop, message=response.message, fraction=response.fraction, complete=stop == "COMPLETE",
                   success=stop == "COMPLETE" and timed is not None and timed.success,
                   path=_path_array(response.path, len(response.joint_names)), joint_names=list(response.joint_names),
                   steps=response.steps, waypoints_reached=response.waypoints_reached,
                   max_position_error=response.max_position_error,
                   max_orientation_error=response.max_orientation_error,
                   max_line_deviation=response.max_line_deviation,
                   trajectory_line_deviation=response.trajectory_line_deviation, timed=timed,
                   warnings=list(response.warnings),
                   request_id=response.request_id, robot_id=response.robot_id, scene_id=response.scene_id,
                   response=response)
