"""Plain Python data (lists, dicts, numpy arrays) to chasles.v1 messages and back.

Every function here accepts either the proto message itself or plain data:

* joint values: a sequence or numpy array of floats [rad] or [m];
* messages: a dict in protobuf JSON form (``lowerCamelCase`` or ``snake_case`` keys, the same
  as the files in ``examples/``), or a JSON string;
* enums: the value's name in any case (``"collocation"``) or its number.

Nothing is validated here beyond types: the server checks values and names the offending field.
"""

from __future__ import annotations

import json
import math
import numbers
import uuid
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Type, TypeVar, Union

import numpy as np
from google.protobuf import json_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from ._stubs import pb

M = TypeVar("M", bound=Message)

#: Joint values: a sequence of floats or a 1-D numpy array [rad] or [m].
JointValues = Union[Sequence[float], np.ndarray]


def plain(value: Any) -> Any:
    """Numpy arrays and scalars (recursively inside dicts and lists) as Python lists and numbers.

    Non-finite floats become the strings protobuf JSON uses ("NaN", "Infinity", "-Infinity").
    """
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return plain(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def to_message(value: Any, cls: Type[M], what: str = "") -> M:
    """A message of type ``cls`` from a message of that type (copied), a dict or a JSON string.

    Raises:
        TypeError: ``value`` is another type, or a dict whose keys or values do not fit ``cls``
            (the message names the field).
    """
    what = what or cls.DESCRIPTOR.name
    if isinstance(value, cls):
        out = cls()
        out.CopyFrom(value)
        return out
    if isinstance(value, Message):
        raise TypeError(f"{what}: expected a {cls.DESCRIPTOR.full_name} or a dict, got a "
                        f"{value.DESCRIPTOR.full_name}")
    if isinstance(value, str):
        try:
            value = json.loads(value)
        except json.JSONDecodeError as error:
            raise TypeError(f"{what}: not JSON text ({error})") from error
    if isinstance(value, Mapping):
        out = cls()
        try:
            json_format.ParseDict(plain(value), out)
        except json_format.ParseError as error:
            raise TypeError(f"{what}: {error}") from error
        return out
    raise TypeError(f"{what}: expected a {cls.DESCRIPTOR.full_name} or a dict, got {type(value).__name__}")


def joint_values(values: JointValues, what: str) -> list:
    """A flat list of floats from a sequence or a 1-D array (NaN and inf pass through)."""
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise TypeError(f"{what}: expected a 1-D sequence of joint values, got shape {array.shape}")
    return array.tolist()


def joint_state(value: Any, what: str = "start") -> pb.JointState:
    """A JointState from joint values, ``{"positions": [...]}`` or a JointState."""
    if isinstance(value, (Message, Mapping, str)):
        return to_message(value, pb.JointState, what)
    return pb.JointState(positions=joint_values(value, what + ".positions"))


def joint_states(path: Any, what: str = "path") -> list:
    """JointStates from an (M, n) array, a list of joint value lists or a list of JointStates."""
    if isinstance(path, np.ndarray):
        if path.ndim != 2:
            raise TypeError(f"{what}: expected an (M, n) array, got shape {path.shape}")
        return [pb.JointState(positions=row.tolist()) for row in path.astype(float)]
    return [joint_state(p, f"{what}[{i}]") for i, p in enumerate(path)]


def pose_message(value: Any, what: str = "pose") -> pb.Pose:
    """A Pose from a Pose message, a dict / JSON text of one, a 4×4 homogeneous matrix, or a
    ``(position, quaternion_xyzw)`` pair."""
    if isinstance(value, (Message, Mapping, str)):
        return to_message(value, pb.Pose, what)
    if isinstance(value, tuple) and len(value) == 2:
        position, quaternion = (np.asarray(v, dtype=float) for v in value)
        if position.shape != (3,) or quaternion.shape != (4,):
            raise TypeError(f"{what}: expected (position[3], quaternion_xyzw[4]), got shapes "
                            f"{position.shape} and {quaternion.shape}")
        x, y, z, w = quaternion.tolist()
    else:
        matrix = np.asarray(value, dtype=float)
        if matrix.shape != (4, 4):
            raise TypeError(f"{what}: expected a Pose, a dict, a 4x4 matrix or (position, quaternion), "
                            f"got shape {matrix.shape}")
        position = matrix[:3, 3]
        x, y, z, w = _quaternion_xyzw(matrix[:3, :3])
    return pb.Pose(position=pb.Vector3(x=float(position[0]), y=float(position[1]), z=float(position[2])),
                   orientation=pb.Quaternion(x=x, y=y, z=z, w=w))


def _quaternion_xyzw(r: np.ndarray) -> Tuple[float, float, float, float]:
    """The unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method: the largest of
    w, x, y, z is found first, so no division by a small number)."""
    trace = float(np.trace(r))
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s
    elif k == 1:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s
    elif k == 2:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        q = (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s
    else:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        q = (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s
    norm = float(np.linalg.norm(q))
    return tuple(float(v) / norm for v in q)  # type: ignore[return-value]


def goal(value: Any) -> Tuple[str, Message]:
    """The PlanRequest ``target``: ("goal", JointGoal) or ("pose_goal", PoseGoal).

    Joint values, a JointGoal or a dict with "positions" are joint goals; a PoseGoal or a dict
    with "pose" (and optionally "link" and tolerances) is a pose goal.
    """
    if isinstance(value, pb.JointGoal):
        return "goal", to_message(value, pb.JointGoal)
    if isinstance(value, pb.PoseGoal):
        return "pose_goal", to_message(value, pb.PoseGoal)
    if isinstance(value, str):
        value = json.loads(value)
    if isinstance(value, Mapping):
        if "pose" in value:
            return "pose_goal", to_message(value, pb.PoseGoal, "pose_goal")
        return "goal", to_message(value, pb.JointGoal, "goal")
    return "goal", pb.JointGoal(positions=joint_values(value, "goal.positions"))


def parameter_value(value: Any, what: str) -> pb.ParameterValue:
    """A ParameterValue from a bool, an int or a float (numpy scalars too)."""
    if isinstance(value, pb.ParameterValue):
        return to_message(value, pb.ParameterValue)
    if isinstance(value, (bool, np.bool_)):
        return pb.ParameterValue(bool_value=bool(value))
    if isinstance(value, numbers.Integral):
        return pb.ParameterValue(int_value=int(value))
    if isinstance(value, numbers.Real):
        return pb.ParameterValue(double_value=float(value))
    raise TypeError(f"{what}: expected a bool, int or float, got {type(value).__name__}")


def planner_config(planner: Any = None, parameters: Optional[Mapping[str, Any]] = None) -> pb.PlannerConfig:
    """A PlannerConfig from a planner id (or a PlannerConfig / dict) and plain parameter values.

    ``parameters`` maps names (``"range"``, per joint ``"resolution[3]"``) to bool, int or float;
    they are added to (and override) the ones ``planner`` already has.
    """
    if planner is None or isinstance(planner, str):
        config = pb.PlannerConfig(planner_id=planner or "")
    else:
        config = to_message(planner, pb.PlannerConfig, "planner")
    for name, value in (parameters or {}).items():
        config.parameters[name].CopyFrom(parameter_value(value, f"parameters[{name!r}]"))
    return config


def enum_value(enum_type: Any, value: Union[str, int], what: str) -> int:
    """An enum's number from its name (any case) or number."""
    if isinstance(value, str):
        try:
            return enum_type.Value(value.upper())
        except ValueError:
            names = [n.lower() for n in enum_type.keys() if not n.endswith("UNSPECIFIED")]
            raise ValueError(f"{what} = {value!r} is not one of {names}") from None
    return int(value)


def trajectory_options(
    trajectory: Any = None,
    *,
    post_processing: Union[str, int, None] = None,
    max_velocity: Optional[JointValues] = None,
    max_acceleration: Optional[JointValues] = None,
    max_jerk: Optional[JointValues] = None,
    max_effort: Optional[JointValues] = None,
    sample_period: Optional[float] = None,
    what: str = "trajectory",
) -> Optional[pb.TrajectoryOptions]:
    """TrajectoryOptions from a message or dict plus keyword overrides; None when all are None."""
    overrides = (post_processing, max_velocity, max_acceleration, max_jerk, max_effort, sample_period)
    if trajectory is None and all(v is None for v in overrides):
        return None
    options = pb.TrajectoryOptions() if trajectory is None else to_message(trajectory, pb.TrajectoryOptions, what)
    if post_processing is not None:
        options.post_processing = enum_value(pb.TrajectoryOptions.PostProcessing, post_processing,
                                             f"{what}.post_processing")
    for name, values in (("max_velocity", max_velocity), ("max_acceleration", max_acceleration),
                         ("max_jerk", max_jerk), ("max_effort", max_effort)):
        if values is not None:
            field = getattr(options, name)
            del field[:]
            field.extend(joint_values(values, f"{what}.{name}"))
    if sample_period is not None:
        options.sample_period = float(sample_period)
    return options


def set_fields(message: Message, fields: Mapping[str, Any], what: str) -> None:
    """Sets fields of ``message`` by name from messages or plain values (dicts, lists, numbers).

    Raises:
        TypeError: a name is not a field of the message, or a value does not fit it.
    """
    for name, value in fields.items():
        if value is None:
            continue
        field = message.DESCRIPTOR.fields_by_name.get(name)
        if field is None:
            known = sorted(message.DESCRIPTOR.fields_by_name)
            raise TypeError(f"{what}: {message.DESCRIPTOR.full_name} has no field {name!r} (fields: {known})")
        if isinstance(value, Message):
            if field.label == FieldDescriptor.LABEL_REPEATED:
                raise TypeError(f"{what}.{name}: expected a list, got one {value.DESCRIPTOR.full_name}")
            getattr(message, name).CopyFrom(value)
            continue
        if (field.label == FieldDescriptor.LABEL_REPEATED and field.message_type is not None
                and not field.message_type.GetOptions().map_entry
                and isinstance(value, (list, tuple)) and value and all(isinstance(v, Message) for v in value)):
            repeated = getattr(message, name)
            del repeated[:]
            repeated.extend(value)
            continue
        if field.enum_type is not None and isinstance(value, str):
            value = field.enum_type.values_by_name.get(value.upper(), None)
            if value is None:
                raise ValueError(f"{what}.{name}: not one of {list(field.enum_type.values_by_name)}")
            value = value.number
        try:
            json_format.ParseDict({name: plain(value)}, message)
        except json_format.ParseError as error:
            raise TypeError(f"{what}.{name}: {error}") from error


def set_sources(request: Message, robot: Any, robot_id: Optional[str], scene: Any, scene_id: Optional[str]) -> None:
    """Sets a request's robot (inline or by id) and scene (inline or by id); None leaves the
    server's default. Giving both forms of one is a TypeError."""
    if robot is not None and robot_id is not None:
        raise TypeError("give robot or robot_id, not both")
    if scene is not None and scene_id is not None:
        raise TypeError("give scene or scene_id, not both")
    if robot is not None:
        request.robot.CopyFrom(to_message(robot, pb.RobotModel, "robot"))
    if robot_id is not None:
        request.robot_id = robot_id
    if scene is not None:
        request.scene.CopyFrom(to_message(scene, pb.Scene, "scene"))
    if scene_id is not None:
        request.scene_id = scene_id


def plan_request(
    start: Any,
    goal_value: Any,
    planner: Any = "rrt_connect",
    parameters: Optional[Mapping[str, Any]] = None,
    *,
    robot: Any = None,
    robot_id: Optional[str] = None,
    scene: Any = None,
    scene_id: Optional[str] = None,
    time_budget: Optional[float] = None,
    seed: Optional[int] = None,
    trajectory: Any = None,
    post_processing: Union[str, int, None] = None,
    max_velocity: Optional[JointValues] = None,
    max_acceleration: Optional[JointValues] = None,
    sample_period: Optional[float] = None,
    request_id: Optional[str] = None,
    **more: Any,
) -> pb.PlanRequest:
    """A PlanRequest from plain data (see ``Client.plan`` for the arguments).

    ``more`` sets any other PlanRequest field by name (``collision_resolution=0.01``,
    ``gravity={"z": -9.81}``, ``workcell={...}``).
    """
    request = pb.PlanRequest()
    set_sources(request, robot, robot_id, scene, scene_id)
    request.start.CopyFrom(joint_state(start, "start"))
    target, message = goal(goal_value)
    getattr(request, target).CopyFrom(message)
    request.planner.CopyFrom(planner_config(planner, parameters))
    if time_budget is not None:
        request.time_budget = float(time_budget)
    if seed is not None:
        request.seed = int(seed)
    options = trajectory_options(trajectory, post_processing=post_processing, max_velocity=max_velocity,
                                 max_acceleration=max_acceleration, sample_period=sample_period)
    if options is not None:
        request.trajectory.CopyFrom(options)
    if request_id is not None:
        request.request_id = request_id
    set_fields(request, more, "PlanRequest")
    return request


def benchmark_problem(value: Any, index: int) -> pb.BenchmarkProblem:
    """A BenchmarkProblem from a BenchmarkProblem, a PlanRequest, or a dict.

    A dict with "request" is a BenchmarkProblem; any other dict is a PlanRequest (optionally with
    a "name"), where "start" and "goal" may be plain joint value lists.
    """
    what = f"problems[{index}]"
    if isinstance(value, pb.BenchmarkProblem):
        return to_message(value, pb.BenchmarkProblem, what)
    if isinstance(value, pb.PlanRequest):
        return pb.BenchmarkProblem(request=value)
    if isinstance(value, Mapping) and "request" in value:
        problem = pb.BenchmarkProblem(name=str(value.get("name", "")))
        problem.request.CopyFrom(plan_request_from(value["request"], what + ".request"))
        extra = set(value) - {"name", "request"}
        if extra:
            raise TypeError(f"{what}: unknown keys {sorted(extra)} (expected 'name' and 'request')")
        return problem
    if isinstance(value, Mapping):
        value = dict(value)
        name = str(value.pop("name", ""))
        return pb.BenchmarkProblem(name=name, request=plan_request_from(value, what))
    raise TypeError(f"{what}: expected a BenchmarkProblem, a PlanRequest or a dict, got {type(value).__name__}")


def plan_request_from(value: Any, what: str = "request") -> pb.PlanRequest:
    """A PlanRequest from a PlanRequest or a dict; "start" and "goal" may be plain lists."""
    if isinstance(value, Mapping):
        value = dict(value)
        for key in ("start", "goal"):
            if key in value and not isinstance(value[key], (Mapping, Message, str)):
                value[key] = {"positions": joint_values(value[key], f"{what}.{key}")}
        messages = {k: v for k, v in value.items() if isinstance(v, Message)}
        request = to_message({k: v for k, v in value.items() if k not in messages}, pb.PlanRequest, what)
        set_fields(request, messages, what)
        return request
    return to_message(value, pb.PlanRequest, what)


def benchmark_config(value: Any, index: int) -> pb.BenchmarkConfig:
    """A BenchmarkConfig from a planner id, a BenchmarkConfig or a dict.

    Dicts: ``{"name": ..., "planner": "prm" | {...}, "parameters": {...}, "trajectory": {...},
    "post_processing": "topp"}``; "parameters" and "post_processing" take plain values.
    """
    what = f"configs[{index}]"
    if isinstance(value, str):
        return pb.BenchmarkConfig(planner=pb.PlannerConfig(planner_id=value))
    if isinstance(value, pb.BenchmarkConfig):
        return to_message(value, pb.BenchmarkConfig, what)
    if isinstance(value, Mapping):
        value = dict(value)
        config = pb.BenchmarkConfig(name=str(value.pop("name", "")))
        config.planner.CopyFrom(planner_config(value.pop("planner", None), value.pop("parameters", None)))
        options = trajectory_options(value.pop("trajectory", None),
                                     post_processing=value.pop("post_processing", None),
                                     what=what + ".trajectory")
        if options is not None:
            config.trajectory.CopyFrom(options)
        if value:
            raise TypeError(f"{what}: unknown keys {sorted(value)} "
                            "(expected name, planner, parameters, trajectory, post_processing)")
        return config
    raise TypeError(f"{what}: expected a planner id, a BenchmarkConfig or a dict, got {type(value).__name__}")


def benchmark_request(
    problems: Sequence[Any],
    configs: Sequence[Any],
    runs: Optional[int] = None,
    run_budget: Optional[float] = None,
    parallelism: Optional[int] = None,
    *,
    seed: Optional[int] = None,
    request_id: Optional[str] = None,
    experiment: Optional[str] = None,
    progress_interval: Optional[float] = None,
) -> pb.BenchmarkRequest:
    """A BenchmarkRequest from plain data (see ``Client.benchmark``); the request id defaults to a
    fresh ``"py-<uuid>"``."""
    request = pb.BenchmarkRequest(request_id=request_id or f"py-{uuid.uuid4().hex[:12]}")
    request.problems.extend(benchmark_problem(p, i) for i, p in enumerate(problems))
    request.configs.extend(benchmark_config(c, i) for i, c in enumerate(configs))
    set_fields(request, {"runs": runs, "run_budget": run_budget, "parallelism": parallelism, "seed": seed,
                         "experiment": experiment, "progress_interval": progress_interval}, "BenchmarkRequest")
    return request


def message_to_dict(message: Message) -> Dict[str, Any]:
    """Every field of ``message`` (defaults included) with snake_case keys and Python values.

    Unlike ``json_format.MessageToDict`` 64-bit integers stay ints and enums become their names.
    """
    out: Dict[str, Any] = {}
    for field in message.DESCRIPTOR.fields:
        value = getattr(message, field.name)
        out[field.name] = _field_value(field, value)
    return out


def _field_value(field: FieldDescriptor, value: Any) -> Any:
    if field.label == FieldDescriptor.LABEL_REPEATED:
        if field.message_type is not None and field.message_type.GetOptions().map_entry:
            value_field = field.message_type.fields_by_name["value"]
            return {k: _single_value(value_field, v) for k, v in value.items()}
        return [_single_value(field, v) for v in value]
    return _single_value(field, value)


def _single_value(field: FieldDescriptor, value: Any) -> Any:
    if field.message_type is not None:
        return message_to_dict(value)
    if field.enum_type is not None:
        entry = field.enum_type.values_by_number.get(value)
        return entry.name if entry is not None else int(value)
    return value


def outcome_name(value: int) -> str:
    """The PlanOutcome name of a number, e.g. ``"SUCCESS"``."""
    entry = pb.PlanOutcome.DESCRIPTOR.values_by_number.get(value)
    return entry.name if entry is not None else str(value)

