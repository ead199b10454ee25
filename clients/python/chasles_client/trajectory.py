"""A timed joint trajectory as numpy arrays."""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Mapping, Optional, Union

import numpy as np
from google.protobuf import json_format
from google.protobuf.message import Message

from ._stubs import pb


@dataclass
class Trajectory:
    """Samples of a timed joint trajectory, in the robot's joint order.

    Attributes:
        t: sample times from the start, shape (N,) [s], increasing.
        q: joint positions, shape (N, n) [rad] or [m].
        qd: joint velocities, shape (N, n) [rad/s] or [m/s].
        qdd: joint accelerations, shape (N, n) [rad/s²] or [m/s²].
        effort: joint torques / forces by inverse dynamics, shape (N, n) [N·m] or [N]; None when
            the server sent none (a robot without inertia on every moving link).
        joint_names: the n joint names.
        duration: the trajectory's duration [s] (the response's, else the last sample time).

    Samples the server did not send (empty velocity or acceleration arrays) are NaN.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    effort: Optional[np.ndarray] = None
    joint_names: List[str] = field(default_factory=list)
    duration: float = 0.0

    @property
    def dof(self) -> int:
        """Number of joints n."""
        return int(self.q.shape[1])

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @classmethod
    def from_message(cls, trajectory: pb.JointTrajectory, duration: Optional[float] = None) -> "Trajectory":
        """Arrays from a chasles.v1.JointTrajectory."""
        names = list(trajectory.joint_names)
        points = trajectory.points
        n = len(names) if names else (len(points[0].positions) if points else 0)
        t = np.array([p.time_from_start for p in points], dtype=float)

        def stack(attribute: str) -> Optional[np.ndarray]:
            rows = [getattr(p, attribute) for p in points]
            if rows and all(len(r) == 0 for r in rows):
                return None
            out = np.full((len(points), n), np.nan)
            for i, row in enumerate(rows):
                if len(row) == n:
                    out[i] = row
                elif len(row) != 0:
                    raise ValueError(f"trajectory.points[{i}].{attribute} has {len(row)} values, expected {n}")
            return out

        empty = np.full((len(points), n), np.nan)
        q = stack("positions")
        qd = stack("velocities")
        qdd = stack("accelerations")
        effort = stack("efforts")
        if duration is None or (duration == 0.0 and len(t) > 0):
            duration = float(t[-1] - t[0]) if len(t) else 0.0
        return cls(t=t, q=empty if q is None else q, qd=empty.copy() if qd is None else qd,
                   qdd=empty.copy() if qdd is None else qdd, effort=effort, joint_names=names,
                   duration=float(duration))

    @classmethod
    def from_knots(cls, knots: Union[Message, Mapping[str, Any]], period: float = 0.01) -> "Trajectory":
        """Samples every ``period`` [s] (and at the end) of a chasles.v1.TrajectoryKnots — the
        compact answer of ``knots_only`` requests and of fleets — by its exact rule: between knots
        i and i + 1 the acceleration is constant, q(t) = q_i + v_i·τ + (v_{i+1} − v_i)·τ²/(2T)."""
        if isinstance(knots, Mapping):
            parsed = pb.TrajectoryKnots()
            json_format.ParseDict(knots, parsed, ignore_unknown_fields=True)
            knots = parsed
        if not period > 0:
            raise ValueError(f"period = {period} must be > 0")
        names = list(knots.joint_names)
        n = len(names)
        times = np.asarray(knots.times, dtype=float)
        if n == 0 or len(times) == 0:
            raise ValueError("the knots are empty")
        q_knots = np.asarray(knots.positions, dtype=float).reshape(len(times), n)
        v_knots = np.asarray(knots.velocities, dtype=float).reshape(len(times), n)
        duration = float(times[-1])
        t = np.append(np.arange(0.0, duration, period), duration)
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
        nxt = np.minimum(i + 1, len(times) - 1)
        span = times[nxt] - times[i]
        tau = (t - times[i])[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(span[:, None] > 0, (v_knots[nxt] - v_knots[i]) / span[:, None], 0.0)
        q = q_knots[i] + v_knots[i] * tau + 0.5 * a * tau * tau
        qd = v_knots[i] + a * tau
        return cls(t=t, q=q, qd=qd, qdd=a, joint_names=names, duration=duration)

    @classmethod
    def from_response(cls, response: Union[Message, Mapping[str, Any]]) -> "Trajectory":
        """The trajectory of a PlanResponse or OptimizeResponse (or a RobotTrajectory of a
        CoordinateResponse, or a bare JointTrajectory), as a message or as its JSON dict (the
        files ``chasles plan --out`` writes)."""
        if isinstance(response, Mapping):
            parsed = pb.PlanResponse()
            json_format.ParseDict(response, parsed, ignore_unknown_fields=True)
            response = parsed
        if isinstance(response, pb.JointTrajectory):
            return cls.from_message(response)
        if isinstance(response, (pb.PlanResponse, pb.OptimizeResponse, pb.RobotTrajectory)):
            return cls.from_message(response.trajectory, response.duration)
        raise TypeError(f"expected a PlanResponse, OptimizeResponse, RobotTrajectory or JointTrajectory, "
                        f"got {type(response).__name__}")

    def to_message(self) -> pb.JointTrajectory:
        """The chasles.v1.JointTrajectory of these samples (efforts included when present)."""
        out = pb.JointTrajectory(joint_names=self.joint_names)
        for i in range(len(self)):
            point = out.points.add(time_from_start=float(self.t[i]), positions=self.q[i].tolist())
            if not np.isnan(self.qd[i]).any():
                point.velocities.extend(self.qd[i].tolist())
            if not np.isnan(self.qdd[i]).any():
                point.accelerations.extend(self.qdd[i].tolist())
            if self.effort is not None:
                point.efforts.extend(self.effort[i].tolist())
        return out

    def positions_at(self, times: Union[float, np.ndarray]) -> np.ndarray:
        """Positions at ``times`` [s] by cubic Hermite interpolation of (q, qd) between samples,
        the way the server reads a trajectory; clamped to the first / last sample outside.
        Shape (len(times), n), or (n,) for a scalar time."""
        scalar = np.ndim(times) == 0
        s = np.clip(np.atleast_1d(np.asarray(times, dtype=float)), self.t[0], self.t[-1])
        i = np.clip(np.searchsorted(self.t, s, side="right") - 1, 0, max(len(self) - 2, 0))
        if len(self) == 1:
            out = np.repeat(self.q[:1], len(s), axis=0)
            return out[0] if scalar else out
        h = (self.t[i + 1] - self.t[i])[:, None]
        u = (s[:, None] - self.t[i][:, None]) / h
        h00 = 2 * u**3 - 3 * u**2 + 1
        h10 = u**3 - 2 * u**2 + u
        h01 = -2 * u**3 + 3 * u**2
        h11 = u**3 - u**2
        out = h00 * self.q[i] + h10 * h * self.qd[i] + h01 * self.q[i + 1] + h11 * h * self.qd[i + 1]
        return out[0] if scalar else out

    def write_csv(self, path: Union[str, os.PathLike]) -> Path:
        """Writes one row per sample: t, then q_, qd_, qdd_ (and effort_) per joint name."""
        path = Path(path)
        names = self.joint_names or [f"joint{j + 1}" for j in range(self.dof)]
        blocks = [("q", self.q), ("qd", self.qd), ("qdd", self.qdd)]
        if self.effort is not None:
            blocks.append(("effort", self.effort))
        with path.open("w", newline="") as stream:
            writer = csv.writer(stream)
            writer.writerow(["t"] + [f"{prefix}_{name}" for prefix, _ in blocks for name in names])
            for i in range(len(self)):
                writer.writerow([repr(float(self.t[i]))] +
                                [repr(float(v)) for _, block in blocks for v in block[i]])
        return path
