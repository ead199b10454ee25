"""The Chasles client: typed calls of chasles.v1.Planning over one gRPC channel."""

from __future__ import annotations

import dataclasses
import json
import os
import socket
import threading
import time
import uuid
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, Iterator, List, Mapping, Optional, Sequence, Union

import grpc
import numpy as np
from google.protobuf.message import Message

from . import _health
from ._stubs import pb, pb_grpc
from .benchmark import BenchmarkProgress, BenchmarkResult, BenchmarkRun
from .convert import (JointValues, joint_state, joint_states, joint_values, plan_request,
                      plan_request_from, pose_message, set_fields, set_sources, to_message, trajectory_options)
from .convert import benchmark_request as build_benchmark_request
from .errors import ChaslesError
from .results import CartesianResult, OptimizeResult, PlannerInfo, PlanResult, ReplanResult, RobotInfo, limits_used
from .trajectory import Trajectory

PathLike = Union[str, "os.PathLike[str]"]


def _read_pem(path: PathLike, what: str) -> bytes:
    try:
        return Path(path).read_bytes()
    except OSError as error:
        raise ValueError(f"{what} {str(path)!r} cannot be read: {error.strerror}") from None


def channel_credentials(*, tls_ca: Optional[PathLike] = None, tls_cert: Optional[PathLike] = None,
                        tls_key: Optional[PathLike] = None, tls_server_name: Optional[str] = None,
                        token: Optional[str] = None,
                        options: Optional[List[Any]] = None) -> Optional[grpc.ChannelCredentials]:
    """The credentials of a channel to chasles-server, or ``None`` for plaintext without a token.

    TLS when ``tls_ca`` is given (mutual with ``tls_cert`` and ``tls_key``); a ``token`` rides on
    every call as ``authorization: Bearer TOKEN`` (over TLS, or over gRPC local credentials, which
    reach loopback servers only). ``tls_server_name`` is appended to ``options`` as the TLS target
    name override. Raises ValueError naming the argument when they do not fit together or a file
    cannot be read.
    """
    if (tls_cert is None) != (tls_key is None):
        raise ValueError("tls_cert and tls_key go together (a client certificate and its private key)")
    if tls_cert is not None and tls_ca is None:
        raise ValueError("tls_cert needs tls_ca: a client certificate is only sent over TLS")
    if tls_server_name and tls_ca is None:
        raise ValueError("tls_server_name needs tls_ca (TLS)")
    if tls_ca is not None:
        credentials = grpc.ssl_channel_credentials(
            root_certificates=_read_pem(tls_ca, "tls_ca"),
            private_key=_read_pem(tls_key, "tls_key") if tls_key is not None else None,
            certificate_chain=_read_pem(tls_cert, "tls_cert") if tls_cert is not None else None)
        if tls_server_name:
            if options is None:
                raise ValueError("tls_server_name needs channel options to set")
            options.append(("grpc.ssl_target_name_override", tls_server_name))
    elif token:
        credentials = grpc.local_channel_credentials(grpc.LocalConnectionType.LOCAL_TCP)
    else:
        return None
    if token:
        credentials = grpc.composite_channel_credentials(credentials, grpc.access_token_call_credentials(token))
    return credentials


#: Default deadline of unary calls [s] (planning budgets are at most 600 s; pass more if needed).
DEFAULT_TIMEOUT = 60.0

#: Methods a client may send again when the server was UNAVAILABLE (a replica down or draining):
#: they change nothing, or nothing twice (content-addressed uploads, create-if-missing).
IDEMPOTENT_METHODS = ("Plan", "ListPlanners", "UploadRobot", "UploadScene", "UpdateScene", "InverseKinematics",
                      "CartesianPath", "Optimize", "Coordinate", "CreateWorkcell")


def service_config(retries: int = 5) -> str:
    """The gRPC service config the client uses: round_robin over the addresses it resolves, and
    up to ``retries`` attempts of the idempotent methods on UNAVAILABLE, backing off 0.1 s × 2ᵏ
    up to 1 s (jittered by gRPC)."""
    return json.dumps({
        "loadBalancingConfig": [{"round_robin": {}}],
        "methodConfig": [{
            "name": [{"service": "chasles.v1.Planning", "method": m} for m in IDEMPOTENT_METHODS],
            "retryPolicy": {"maxAttempts": max(2, min(int(retries), 5)), "initialBackoff": "0.1s",
                            "maxBackoff": "1s", "backoffMultiplier": 2,
                            "retryableStatusCodes": ["UNAVAILABLE"]},
        }],
    })


def channel_target(address: Union[str, Sequence[str]]) -> str:
    """A gRPC target for one ``host:port``, or several (a comma-separated string or a list):
    each host resolved here to its addresses, all of them balanced round-robin by the channel."""
    addresses = [a.strip() for a in (address.split(",") if isinstance(address, str) else address) if a.strip()]
    if not addresses:
        raise ValueError("address is empty: give host:port, or several separated by commas")
    if len(addresses) == 1:
        return addresses[0]
    resolved = []
    for a in addresses:
        host, _, port = a.rpartition(":")
        if not host or not port.isdigit():
            raise ValueError(f"address '{a}' must be host:port")
        host = host.strip("[]")
        for family, _, _, _, sockaddr in socket.getaddrinfo(host, int(port), proto=socket.IPPROTO_TCP):
            text = f"[{sockaddr[0]}]:{port}" if family == socket.AF_INET6 else f"{sockaddr[0]}:{port}"
            if text not in resolved:
                resolved.append(text)
    v6 = [r for r in resolved if r.startswith("[")]
    if v6 and len(v6) != len(resolved):
        raise ValueError("addresses mix IPv4 and IPv6; give one family")
    return ("ipv6:" if v6 else "ipv4:") + ",".join(resolved)



def fleet_message(name: str, goals: Optional[Mapping[str, Sequence[float]]],
                  states: Optional[Mapping[str, Sequence[float]]], now: float = 0.0,
                  state_tolerance: float = 0.0) -> pb.AssignFleetGoalsRequest:
    """An AssignFleetGoalsRequest: goals ``{robot: (x, y, θ)}``, states ``{robot: (x, y)}``."""
    message = pb.AssignFleetGoalsRequest(name=name, now=now, state_tolerance=state_tolerance)
    for robot, positions in (goals or {}).items():
        message.goals.add(robot=robot, positions=[float(v) for v in positions])
    for robot, position in (states or {}).items():
        x, y = (float(v) for v in position)
        message.states.add(robot=robot, x=x, y=y)
    return message

class Client:
    """A connection to a chasles-server.

    Args:
        address: ``host:port`` of the server, or of several replicas (``"a:50051,b:50051"`` or a
            list): calls are spread round-robin over them, and the idempotent methods
            (IDEMPOTENT_METHODS) are retried on UNAVAILABLE with backoff, so a replica that goes
            down costs no failed call while another answers.
        retries: attempts of an idempotent call on UNAVAILABLE, in [2, 5] (gRPC's cap).
        timeout: default deadline of each unary call [s]; ``None`` = no deadline. Every method
            also takes its own ``timeout``. A plan's ``time_budget`` must fit in it.
        max_message_mb: largest message sent or received [MiB] (the server's default is 64).
        channel: an existing channel to use instead of opening one (``address`` and the TLS and
            token arguments are then ignored).
        tls_ca: PEM file of the CA the server certificate must chain to; enables TLS.
        tls_cert, tls_key: PEM files of a client certificate and its key, for mutual TLS
            (both or neither; need ``tls_ca``).
        tls_server_name: the name to verify in the server certificate instead of the address's host.
        token: a bearer token of the server's ``--tokens`` file; every call then carries
            ``authorization: Bearer TOKEN``. Without TLS it is sent over gRPC local credentials,
            which reach loopback servers only.

    Every call raises ``ChaslesError`` (status code and the server's message) when the RPC fails;
    an expected planning failure (no path within the budget) is a result, not an exception.
    The client is usable from several threads at once (gRPC channels are thread-safe).
    """

    def __init__(self, address: Union[str, Sequence[str]] = "127.0.0.1:50051",
                 timeout: Optional[float] = DEFAULT_TIMEOUT, *,
                 max_message_mb: int = 64, channel: Optional[grpc.Channel] = None,
                 tls_ca: Optional[PathLike] = None, tls_cert: Optional[PathLike] = None,
                 tls_key: Optional[PathLike] = None, tls_server_name: Optional[str] = None,
                 token: Optional[str] = None, retries: int = 5) -> None:
        self.address = address
        self.timeout = timeout
        # Each replica on its own, for benchmarks spread over them (benchmark_request).
        self._replicas: List[str] = []
        if channel is None:
            listed = [a.strip() for a in (address.split(",") if isinstance(address, str) else address) if a.strip()]
            if len(listed) > 1:
                self._replicas = listed
            self._replica_options = dict(max_message_mb=max_message_mb, tls_ca=tls_ca, tls_cert=tls_cert,
                                         tls_key=tls_key, tls_server_name=tls_server_name, token=token)
            size = int(max_message_mb) * 1024 * 1024
            options = [("grpc.max_send_message_length", size), ("grpc.max_receive_message_length", size),
                       ("grpc.enable_retries", 1), ("grpc.service_config", service_config(retries))]
            credentials = channel_credentials(tls_ca=tls_ca, tls_cert=tls_cert, tls_key=tls_key,
                                              tls_server_name=tls_server_name, token=token, options=options)
            target = channel_target(address)
            if credentials is None:
                channel = grpc.insecure_channel(target, options=options)
            else:
                channel = grpc.secure_channel(target, credentials, options=options)
            self._owns_channel = True
        else:
            self._owns_channel = False
        self._channel = channel
        self._stub = pb_grpc.PlanningStub(channel)
        self._health_check = channel.unary_unary(
            _health.CHECK_METHOD, request_serializer=_health.HealthCheckRequest.SerializeToString,
            response_deserializer=_health.HealthCheckResponse.FromString)
        self._robots: Dict[str, RobotInfo] = {}

    # -- connection -----------------------------------------------------------------------------

    @property
    def stub(self) -> pb_grpc.PlanningStub:
        """The generated stub, for calls this class does not wrap (InverseKinematics, Coordinate…)."""
        return self._stub

    def close(self) -> None:
        """Closes the channel (when this client opened it)."""
        if self._owns_channel:
            self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _call(self, method: str, request: Message, timeout: Optional[float]) -> Any:
        try:
            return getattr(self._stub, method)(request, timeout=self._timeout(timeout))
        except grpc.RpcError as error:
            raise ChaslesError.from_rpc_error(error, method) from None

    def _timeout(self, timeout: Optional[float]) -> Optional[float]:
        return self.timeout if timeout is None else timeout

    def health(self, service: str = "", timeout: Optional[float] = None) -> str:
        """The standard gRPC health check: ``"SERVING"``, ``"NOT_SERVING"`` or ``"SERVICE_UNKNOWN"``.

        ``service`` = ``""`` (the whole server) or ``"chasles.v1.Planning"``.
        """
        try:
            response = self._health_check(_health.HealthCheckRequest(service=service), timeout=self._timeout(timeout))
        except grpc.RpcError as error:
            raise ChaslesError.from_rpc_error(error, "Health.Check") from None
        return _health.status_name(response)

    def wait_until_serving(self, timeout: float = 10.0) -> None:
        """Waits until the server answers the health check with SERVING.

        Raises:
            ChaslesError: DEADLINE_EXCEEDED when it did not within ``timeout`` [s] (the last
                status or error is in the message).
        """
        deadline = time.monotonic() + timeout
        last = "no answer"
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise ChaslesError(grpc.StatusCode.DEADLINE_EXCEEDED,
                                   f"server at {self.address} not serving after {timeout:g} s ({last})", "Health.Check")
            try:
                grpc.channel_ready_future(self._channel).result(timeout=left)
                last = self.health(timeout=max(min(left, 2.0), 0.05))
                if last == "SERVING":
                    return
            except grpc.FutureTimeoutError:
                last = "channel not ready"
            except ChaslesError as error:
                last = str(error)
            time.sleep(0.05)

    # -- catalogue and uploads ------------------------------------------------------------------

    def planners(self, timeout: Optional[float] = None) -> List[PlannerInfo]:
        """The server's planners with their typed parameters, defaults and ranges."""
        response = self._call("ListPlanners", pb.ListPlannersRequest(), timeout)
        return [PlannerInfo.from_message(p) for p in response.planners]

    def upload_robot(self, urdf: Union[str, os.PathLike, Message, Mapping[str, Any]], srdf: Union[str, os.PathLike] = "",
                     meshes: Optional[Mapping[str, Union[bytes, str, os.PathLike]]] = None, *,
                     name: str = "", strict_srdf: bool = False, exact_meshes: bool = False,
                     timeout: Optional[float] = None) -> str:
        """Stores a robot on the server and returns its id (a content hash) for ``robot_id``.

        Args:
            urdf: URDF XML text or a path to a .urdf file; or a whole RobotModel (message or dict,
                e.g. a DH or mobile robot from ``examples/robots/*.json``), then srdf/meshes unused.
            srdf: SRDF XML text or a path to a .srdf file; its disabled collision pairs are honoured
                (pairs naming links the URDF lacks are skipped, listed in
                ``robot_info(robot_id).warnings``; ``strict_srdf=True`` makes them an error).
            meshes: mesh files the URDF references, keyed by the exact ``filename`` of its
                ``<mesh>`` tags: bytes, or a path to read.
            name: default robot name used in messages.
            exact_meshes: keep mesh collision geometry exact (FCL, discrete checks) instead of the
                spheres the server fits to it at upload (``robot_info(robot_id).collision_model``).

        The joints and limits the server answered are kept: ``robot_info(robot_id)``, and plans
        with this robot (also as the server's default robot, when it is the same model) carry
        their velocity and acceleration limits.
        """
        if isinstance(urdf, (Message, Mapping)):
            model = to_message(urdf, pb.RobotModel, "robot")
        else:
            model = pb.RobotModel(name=name)
            model.urdf.urdf = _text(urdf)
            model.urdf.srdf = _text(srdf) if srdf else ""
            model.urdf.strict_srdf = strict_srdf
            model.urdf.exact_meshes = exact_meshes
            for filename, data in (meshes or {}).items():
                model.urdf.mesh_files[filename] = data if isinstance(data, bytes) else Path(data).read_bytes()
        if name:
            model.name = name
        response = self._call("UploadRobot", pb.UploadRobotRequest(robot=model), timeout)
        self._robots[response.robot_id] = RobotInfo.from_response(response)
        return response.robot_id

    def robot_info(self, robot_id: str) -> Optional[RobotInfo]:
        """Joints and limits of a robot this client uploaded (None for others)."""
        return self._robots.get(robot_id)

    def upload_scene(self, scene: Union[Message, Mapping[str, Any], str, os.PathLike],
                     timeout: Optional[float] = None) -> str:
        """Stores a scene (a Scene message, a dict in protobuf JSON form, or a path to a .json file)
        and returns its id for ``scene_id``."""
        if isinstance(scene, os.PathLike) or (isinstance(scene, str) and not scene.lstrip().startswith("{")):
            scene = Path(scene).read_text()
        message = to_message(scene, pb.Scene, "scene")
        return self._call("UploadScene", pb.UploadSceneRequest(scene=message), timeout).scene_id

    # -- planning -------------------------------------------------------------------------------

    def plan(self, start: Any, goal: Any, planner: Any = "rrt_connect", parameters: Optional[Mapping[str, Any]] = None,
             *, robot: Any = None, robot_id: Optional[str] = None, scene: Any = None, scene_id: Optional[str] = None,
             time_budget: Optional[float] = None, seed: Optional[int] = None, post_processing: Union[str, int, None] = None,
             max_velocity: Optional[JointValues] = None, max_acceleration: Optional[JointValues] = None,
             sample_period: Optional[float] = None, trajectory: Any = None, request_id: Optional[str] = None,
             timeout: Optional[float] = None, **more: Any) -> PlanResult:
        """Plans from ``start`` to ``goal`` and returns the verified trajectory.

        Args:
            start: joint positions [rad] (a sequence, a numpy array or a JointState).
            goal: joint positions, a JointGoal / ``{"positions": [...], "tolerance": ...}``, or a pose
                goal (a PoseGoal or ``{"link": "tool", "pose": {...}}``).
            planner: planner id (``planners()`` lists them), or a PlannerConfig / dict.
            parameters: planner parameters by name, plain bool / int / float values.
            robot, robot_id: an inline RobotModel or an uploaded robot's id; neither = the server's
                default robot.
            scene, scene_id: an inline Scene (message or dict) or an uploaded scene's id; neither =
                the server's default scene.
            time_budget: planning budget [s] (server default 5 s).
            seed: random seed (server default 1).
            post_processing: "topp", "collocation", "spline" or "none" (server default: TOPP).
            max_velocity, max_acceleration: per-joint limits [rad/s], [rad/s²].
            sample_period: period of the returned samples [s].
            trajectory: a whole TrajectoryOptions (message or dict); the keywords above override it.
            request_id: echoed in the server log and the result.
            timeout: deadline of this call [s] (default: the client's).
            more: any other PlanRequest field by name, e.g. ``collision_resolution=0.01``, or
                ``group="left_arm"`` to plan one SRDF planning group (``RobotInfo.groups``): ``start``
                holds every joint, ``goal`` the group's (or every joint), the result the group's.

        Returns:
            PlanResult: check ``success`` / ``outcome``; planning failures are not exceptions.

        Raises:
            ChaslesError: the server rejected the request (INVALID_ARGUMENT naming the field,
                NOT_FOUND for an unknown id or planner, …) or the call failed.
        """
        request = plan_request(start, goal, planner, parameters, robot=robot, robot_id=robot_id, scene=scene,
                               scene_id=scene_id, time_budget=time_budget, seed=seed, trajectory=trajectory,
                               post_processing=post_processing, max_velocity=max_velocity,
                               max_acceleration=max_acceleration, sample_period=sample_period,
                               request_id=request_id, **more)
        return self.plan_request(request, timeout=timeout)

    def plan_request(self, request: Union[Message, Mapping[str, Any], str], timeout: Optional[float] = None) -> PlanResult:
        """Sends a whole PlanRequest (message, dict or JSON text, e.g. ``examples/requests/*.json``)."""
        message = plan_request_from(request) if not isinstance(request, str) else to_message(request, pb.PlanRequest)
        response = self._call("Plan", message, timeout)
        velocity, acceleration = limits_used(message.trajectory if message.HasField("trajectory") else None,
                                             self._model_velocity(response.robot_id))
        result = PlanResult.from_response(response, velocity, acceleration)
        result.request = message
        return result

    def optimize(self, path: Any, *, robot: Any = None, robot_id: Optional[str] = None, scene: Any = None,
                 scene_id: Optional[str] = None, post_processing: Union[str, int, None] = None,
                 max_velocity: Optional[JointValues] = None, max_acceleration: Optional[JointValues] = None,
                 sample_period: Optional[float] = None, options: Any = None,
                 start_velocity: Optional[JointValues] = None, end_velocity: Optional[JointValues] = None,
                 time_budget: Optional[float] = None, request_id: Optional[str] = None,
                 timeout: Optional[float] = None, **more: Any) -> OptimizeResult:
        """Turns a path of your own into an optimised, verified trajectory.

        Args:
            path: waypoints as an (M, n) array / list of joint value lists / JointStates; or a
                Trajectory or JointTrajectory (its positions are the path, its timing only gives
                the boundary velocities).
            post_processing: "topp" (default), "collocation", "spline" or "none".
            options: a whole TrajectoryOptions (message or dict); the keywords override it.
            start_velocity, end_velocity: boundary velocities [rad/s]; default at rest.
            time_budget: [s] (server default 10 s).
            Others as in ``plan``; ``more`` sets any other OptimizeRequest field by name.
        """
        request = pb.OptimizeRequest()
        set_sources(request, robot, robot_id, scene, scene_id)
        if isinstance(path, Trajectory):
            request.trajectory.CopyFrom(path.to_message())
        elif isinstance(path, pb.JointTrajectory):
            request.trajectory.CopyFrom(path)
        else:
            request.path.extend(joint_states(path))
        trajectory = trajectory_options(options, post_processing=post_processing, max_velocity=max_velocity,
                                        max_acceleration=max_acceleration, sample_period=sample_period,
                                        what="options")
        if trajectory is not None:
            request.options.CopyFrom(trajectory)
        if start_velocity is not None:
            request.start_velocity.extend(joint_values(start_velocity, "start_velocity"))
        if end_velocity is not None:
            request.end_velocity.extend(joint_values(end_velocity, "end_velocity"))
        if time_budget is not None:
            request.time_budget = float(time_budget)
        if request_id is not None:
            request.request_id = request_id
        set_fields(request, more, "OptimizeRequest")
        return self.optimize_request(request, timeout=timeout)

    def optimize_request(self, request: Union[Message, Mapping[str, Any], str],
                         timeout: Optional[float] = None) -> OptimizeResult:
        """Sends a whole OptimizeRequest (message, dict or JSON text)."""
        message = to_message(request, pb.OptimizeRequest, "OptimizeRequest")
        response = self._call("Optimize", message, timeout)
        velocity, acceleration = limits_used(message.options if message.HasField("options") else None,
                                             self._model_velocity(response.robot_id))
        result = OptimizeResult.from_response(response, velocity, acceleration)
        result.request = message
        return result

    def cartesian_path(self, start: Any, waypoints: Sequence[Any], link: str = "", *, robot: Any = None,
                       robot_id: Optional[str] = None, scene: Any = None, scene_id: Optional[str] = None,
                       max_step: Optional[float] = None, max_rotation_step: Optional[float] = None,
                       max_joint_jump: Optional[float] = None, jump_threshold: Optional[float] = None,
                       avoid_collisions: bool = True, post_processing: Union[str, int, None] = None,
                       sample_period: Optional[float] = None, options: Any = None,
                       request_id: Optional[str] = None, timeout: Optional[float] = None,
                       **more: Any) -> CartesianResult:
        """Drives ``link`` along straight lines in task space (MoveIt's computeCartesianPath) and
        returns the states achieved, timed.

        Args:
            start: joint positions [rad].
            waypoints: link poses in the base frame, in order: Pose messages, dicts
                ``{"position": {"x": …}, "orientation": {"x": …, "w": …}}``, 4×4 homogeneous
                matrices, or ``(position, quaternion_xyzw)`` pairs.
            link: the link that moves; empty = "tool" if the robot has one, else the last link.
            max_step: [m] link translation between states (server default 0.01).
            max_rotation_step: [rad] link rotation between states (default 0.05).
            max_joint_jump: [rad] largest joint change between states (default 0.2).
            jump_threshold: MoveIt's relative jump test (× the mean step); 0 / None = off.
            avoid_collisions: False checks nothing (MoveIt's avoid_collisions = False; the timing
                still refuses a path that collides).
            post_processing, sample_period, options: how the states are timed, as in ``optimize``.
            more: any other CartesianPathRequest field by name, e.g. ``position_tolerance=1e-3``.

        Returns:
            CartesianResult: ``stop`` and ``fraction`` say how far it got; ``timed`` is the timed
            trajectory (None when fewer than two states were achieved).
        """
        request = pb.CartesianPathRequest()
        set_sources(request, robot, robot_id, scene, scene_id)
        request.start.CopyFrom(joint_state(start))
        request.link = link
        for i, waypoint in enumerate(waypoints):
            request.waypoints.append(pose_message(waypoint, f"waypoints[{i}]"))
        for name, value in (("max_step", max_step), ("max_rotation_step", max_rotation_step),
                            ("max_joint_jump", max_joint_jump), ("jump_threshold", jump_threshold)):
            if value is not None:
                setattr(request, name, float(value))
        request.ignore_collisions = not avoid_collisions
        timing = trajectory_options(options, post_processing=post_processing, sample_period=sample_period,
                                    what="options")
        if timing is not None:
            request.options.CopyFrom(timing)
        if request_id is not None:
            request.request_id = request_id
        set_fields(request, more, "CartesianPathRequest")
        return self.cartesian_path_request(request, timeout)

    def cartesian_path_request(self, request: Union[Message, Mapping[str, Any], str],
                               timeout: Optional[float] = None) -> CartesianResult:
        """Sends a whole CartesianPathRequest (message, dict or JSON text, e.g. the contents of
        ``examples/requests/cartesian_panda_table.json``)."""
        message = to_message(request, pb.CartesianPathRequest, "CartesianPathRequest")
        response = self._call("CartesianPath", message, timeout)
        velocity, acceleration = limits_used(message.options if message.HasField("options") else None,
                                             self._model_velocity(response.robot_id))
        return CartesianResult.from_response(response, velocity, acceleration)

    # -- several robots -----------------------------------------------------------------------

    def coordinate(self, request: Union[Message, Mapping[str, Any], str, os.PathLike],
                   timeout: Optional[float] = None) -> Any:
        """Sends a CoordinateRequest (message, dict, JSON text or a .json file such as
        ``examples/requests/coordinate_fleet.json``) and returns the CoordinateResponse. A fleet's
        robots come back as knots: ``Trajectory.from_knots(response.robots[k].knots)`` samples one.
        The deadline defaults to the request's budget + 30 s."""
        if isinstance(request, os.PathLike) or (isinstance(request, str) and request.endswith(".json")
                                                 and Path(request).is_file()):
            request = Path(request).read_text(encoding="utf-8")
        message = to_message(request, pb.CoordinateRequest, "CoordinateRequest")
        if timeout is None:
            timeout = (message.time_budget or 30.0) + 30.0
        return self._call("Coordinate", message, timeout)

    # -- fleet sessions (goals that keep coming) -----------------------------------------------

    def open_fleet_session(self, name: str, request: Union[Message, Mapping[str, Any], str, os.PathLike],
                           timeout: Optional[float] = 120.0) -> Any:
        """Opens fleet session ``name`` for the scene and robots of ``request`` (an
        OpenFleetSessionRequest, or a CoordinateRequest such as
        ``examples/requests/coordinate_fleet.json``: its scene, robots and fleet_resolution; the
        goals are ignored) and returns the OpenFleetSessionResponse."""
        if isinstance(request, os.PathLike) or (isinstance(request, str) and request.endswith(".json")
                                                 and Path(request).is_file()):
            request = Path(request).read_text(encoding="utf-8")
        message = None
        if not isinstance(request, pb.CoordinateRequest):
            try:
                message = to_message(request, pb.OpenFleetSessionRequest, "OpenFleetSessionRequest")
            except TypeError:
                if not isinstance(request, (str, Mapping)):
                    raise
        if message is None:  # a CoordinateRequest: its scene, robots and lattice
            team = to_message(request, pb.CoordinateRequest, "CoordinateRequest")
            message = pb.OpenFleetSessionRequest(fleet_resolution=team.fleet_resolution,
                                                 robot_padding=team.robot_padding)
            if team.HasField("scene"):
                message.scene.CopyFrom(team.scene)
            elif team.scene_id:
                message.scene_id = team.scene_id
            for robot in team.robots:
                added = message.robots.add()
                added.CopyFrom(robot)
                added.ClearField("goal")
        message.name = name
        return self._call("OpenFleetSession", message, timeout)

    def assign_fleet_goals(self, name: str, goals: Optional[Mapping[str, Sequence[float]]] = None, now: float = 0.0,
                           timeout: Optional[float] = 60.0, *,
                           states: Optional[Mapping[str, Sequence[float]]] = None,
                           state_tolerance: float = 0.0) -> Any:
        """Sends goals ``{robot name: (x, y, θ)}`` to session ``name``, answered in order from
        ``now`` (server clock, s since the epoch; 0 = now). ``states`` ``{robot name: (x, y)}``
        are where robots stand at ``now``, applied first: a robot behind its plan is LATE and its
        plan, and those of the robots ordered after it, are delayed (within ``state_tolerance``
        [m] of its plan it is ON_PLAN; 0 = 0.05 m). Returns the AssignFleetGoalsResponse: a
        result per goal and per state, the new plans (``Trajectory.from_knots(plan.knots)``
        samples one, from ``plan.start_time``) and the orders at shared nodes."""
        return self._call("AssignFleetGoals", fleet_message(name, goals, states, now, state_tolerance), timeout)

    def stream_fleet_session(self, messages: Iterable[Any], timeout: Optional[float] = None) -> Iterator[Any]:
        """One StreamFleetSession call: ``messages`` yields AssignFleetGoalsRequests (or dicts
        ``{"name", "now", "goals": {robot: (x, y, θ)}, "states": {robot: (x, y)},
        "state_tolerance"}``; a message without a name is for the stream's first session) as
        the executor produces them; the answers (AssignFleetGoalsResponse) come back one per
        message, in order. Ends when ``messages`` does.

        Raises:
            ChaslesError: a bad message ends the stream; the error names the message's index.
        """
        def requests() -> Iterator[pb.AssignFleetGoalsRequest]:
            for item in messages:
                if isinstance(item, pb.AssignFleetGoalsRequest):
                    yield item
                else:
                    yield fleet_message(item.get("name", ""), item.get("goals"), item.get("states"),
                                        item.get("now", 0.0), item.get("state_tolerance", 0.0))

        call = self._stub.StreamFleetSession(requests(), timeout=timeout)
        try:
            yield from call
        except grpc.RpcError as error:
            raise ChaslesError.from_rpc_error(error, "StreamFleetSession") from None
        finally:
            call.cancel()  # (a no-op once the stream has ended)

    def replan(self, messages: Iterable[Any], timeout: Optional[float] = None) -> Iterator[ReplanResult]:
        """One Replan stream: ``messages`` yields ReplanRequests (or dicts of their fields, e.g.
        ``{"plan": {...}}`` first, then ``{"time": 2.0, "state": {"positions": [...]}}``,
        ``{"time": 3.0, "scene": {...}}`` or ``{"time": 4.0, "moving_obstacles_changed": True,
        "moving_obstacles": [...]}``) as the robot moves; one ReplanResult comes back per message,
        in order: the current trajectory's rest while it holds (``action == "KEPT"``), else a new
        trajectory from the robot's state (braking first when it is moving). Ends when
        ``messages`` does.

        Raises:
            ChaslesError: a bad message ends the stream; the error names the message's index.
        """
        def requests() -> Iterator[pb.ReplanRequest]:
            for item in messages:
                yield item if isinstance(item, pb.ReplanRequest) else replan_message(item)

        call = self._stub.Replan(requests(), timeout=self._timeout(timeout))
        try:
            for response in call:
                yield ReplanResult.from_response(response)
        except grpc.RpcError as error:
            raise ChaslesError.from_rpc_error(error, "Replan") from None
        finally:
            call.cancel()  # (a no-op once the stream has ended)

    def close_fleet_session(self, name: str, timeout: Optional[float] = 30.0) -> bool:
        """Closes session ``name``; False when it was not open."""
        return self._call("CloseFleetSession", pb.CloseFleetSessionRequest(name=name), timeout).closed

    def _model_velocity(self, robot_id: str) -> Optional[np.ndarray]:
        info = self._robots.get(robot_id)
        return None if info is None else info.velocity_limits

    # -- benchmarking ---------------------------------------------------------------------------

    def benchmark(self, problems: Sequence[Any], configs: Sequence[Any], runs: Optional[int] = None,
                  run_budget: Optional[float] = None, parallelism: Optional[int] = None, *,
                  seed: Optional[int] = None, request_id: Optional[str] = None, experiment: Optional[str] = None,
                  progress_interval: Optional[float] = None,
                  on_progress: Optional[Callable[[BenchmarkProgress], Any]] = None,
                  on_run: Optional[Callable[[BenchmarkRun], Any]] = None,
                  timeout: Optional[float] = None) -> BenchmarkResult:
        """Runs every problem × configuration × run on the server and collects the results.

        Args:
            problems: PlanRequests (messages or dicts, "start" and "goal" may be plain lists; an
                optional "name"), or BenchmarkProblems / ``{"name": ..., "request": ...}``.
            configs: planner ids (``"rrt_connect"``), BenchmarkConfigs, or dicts
                ``{"name", "planner", "parameters", "trajectory", "post_processing"}``.
            runs: runs per problem and configuration (server default 10).
            run_budget: planning budget of each run [s] (server default 5).
            parallelism: runs at once (server default: its worker threads).
            seed: run r is seeded seed + r in every problem and configuration (server default 1).
            request_id: the benchmark's id for ``stop_benchmark``; default a fresh
                ``"py-<uuid>"`` (known before the call, so another thread can stop it).
            experiment: experiment name in the OMPL logs.
            progress_interval: least time between progress-only messages [s].
            on_progress: called with a BenchmarkProgress for every message of the stream.
            on_run: called with each BenchmarkRun as it finishes.
            timeout: deadline of the whole benchmark [s]; default none (not the client's timeout).

        Returns:
            BenchmarkResult (``stopped`` when StopBenchmark ended it early).

        Raises:
            ChaslesError: the server rejected the request or the stream failed; KeyboardInterrupt
                cancels the call on the server before it propagates.
        """
        request = build_benchmark_request(problems, configs, runs, run_budget, parallelism, seed=seed,
                                          request_id=request_id, experiment=experiment,
                                          progress_interval=progress_interval)
        return self.benchmark_request(request, on_progress=on_progress, on_run=on_run, timeout=timeout)

    def benchmark_request(self, request: Union[Message, Mapping[str, Any], str],
                              on_progress: Optional[Callable[[BenchmarkProgress], Any]] = None,
                              on_run: Optional[Callable[[BenchmarkRun], Any]] = None,
                              timeout: Optional[float] = None) -> BenchmarkResult:
        """Sends a whole BenchmarkRequest (message, dict or JSON text) and consumes its stream.

        A client of several replicas spreads the runs over them: replica k runs its share from
        run ``first`` on, seeded ``seed + first`` (so every run is the one a single server would
        make), in parallel; the answers are merged into one result (runs renumbered, summaries
        recomputed, OMPL logs merged). ``on_run`` is then called from the replicas' threads."""
        message = to_message(request, pb.BenchmarkRequest, "BenchmarkRequest")
        if not message.request_id:  # known before the call, so another thread can stop it
            message.request_id = f"py-{uuid.uuid4().hex[:12]}"
        if self._replicas:
            return self._benchmark_shards(message, on_progress, on_run, timeout)
        call = self._stub.Benchmark(message, timeout=timeout)
        try:
            return BenchmarkResult.from_stream(call, message, on_progress=on_progress, on_run=on_run)
        except grpc.RpcError as error:
            raise ChaslesError.from_rpc_error(error, "Benchmark") from None
        except BaseException:
            call.cancel()
            raise

    def _benchmark_shards(self, message: pb.BenchmarkRequest,
                          on_progress: Optional[Callable[[BenchmarkProgress], Any]],
                          on_run: Optional[Callable[[BenchmarkRun], Any]],
                          timeout: Optional[float]) -> BenchmarkResult:
        total_runs = message.runs or 10
        first_seed = message.seed or 1
        shards = []
        first = 0
        for k, address in enumerate(self._replicas):
            share = total_runs // len(self._replicas) + (1 if k < total_runs % len(self._replicas) else 0)
            if share == 0:
                continue
            part = pb.BenchmarkRequest()
            part.CopyFrom(message)
            part.runs = share
            part.seed = first_seed + first
            part.request_id = f"{message.request_id}-{k}"
            shards.append((address, part, first))
            first += share
        results: List[Optional[BenchmarkResult]] = [None] * len(shards)
        errors: List[BaseException] = []
        lock = threading.Lock()
        progress = [BenchmarkProgress(0, 0, 0, 0.0, -1.0) for _ in shards]
        started = time.monotonic()

        def run(k: int) -> None:
            address, part, offset = shards[k]

            def shard_progress(p: BenchmarkProgress) -> None:
                if on_progress is None:
                    return
                with lock:
                    progress[k] = p
                    on_progress(BenchmarkProgress(sum(q.done for q in progress), total_runs * len(
                        part.problems) * len(part.configs), sum(q.running for q in progress),
                        time.monotonic() - started, max(q.eta for q in progress)))

            def shard_run(r: BenchmarkRun) -> None:
                if on_run is not None:
                    on_run(dataclasses.replace(r, run=r.run + offset))

            try:
                with Client(address, timeout=self.timeout, **self._replica_options) as replica:
                    results[k] = replica.benchmark_request(part, on_progress=shard_progress, on_run=shard_run,
                                                           timeout=timeout)
            except BaseException as error:  # noqa: BLE001 - re-raised below
                with lock:
                    errors.append(error)

        threads = [threading.Thread(target=run, args=(k,)) for k in range(len(shards))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if errors:
            raise errors[0]
        return BenchmarkResult.merge([r for r in results if r is not None], [s[2] for s in shards],
                                     message.request_id, time.monotonic() - started)

    def stop_benchmark(self, request_id: str, timeout: Optional[float] = None) -> bool:
        """Stops a running benchmark; its ``benchmark`` call still returns the finished runs.

        Returns True when it was running and is now stopping.
        """
        return self._call("StopBenchmark", pb.StopBenchmarkRequest(request_id=request_id), timeout).stopped


def replan_message(fields: Mapping[str, Any]) -> pb.ReplanRequest:
    """A ReplanRequest from a dict of its fields (``plan`` may already be a PlanRequest)."""
    fields = dict(fields)
    plan = fields.pop("plan", None)
    message = to_message(fields, pb.ReplanRequest, "replan message")
    if plan is not None:
        message.plan.CopyFrom(plan if isinstance(plan, pb.PlanRequest) else plan_request_from(plan, "plan"))
    return message


def _text(value: Union[str, os.PathLike]) -> str:
    """XML text as given, or the content of a file path."""
    if isinstance(value, os.PathLike):
        return Path(value).read_text()
    if not value.lstrip().startswith("<") and len(value) < 4096 and Path(value).is_file():
        return Path(value).read_text()
    return value


__all__ = ["Client", "DEFAULT_TIMEOUT"]
