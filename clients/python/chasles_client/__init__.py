"""Python client of the Chasles motion planning server (gRPC service chasles.v1.Planning).

    from chasles_client import Client
    with Client("127.0.0.1:50051") as client:
        result = client.plan(start=[0, -0.785, 0, -2.356, 0, 1.571, 0.785],
                             goal=[-1, -0.3, 0, -2.2, 0, 1.9, 0.785])
        print(result.outcome, result.trajectory.duration)

Needs the generated stubs (``chasles.v1.chasles_pb2``) on the path: the build writes them to
``build/python`` (see clients/python/README.md).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# Names are imported on first use, so `python3 -m chasles_client --help` works before the stubs exist.
_EXPORTS = {
    "BenchmarkProgress": "benchmark",
    "BenchmarkResult": "benchmark",
    "BenchmarkRun": "benchmark",
    "ConfigSummary": "benchmark",
    "CartesianResult": "results",
    "Client": "client",
    "DEFAULT_TIMEOUT": "client",
    "ChaslesError": "errors",
    "OptimizeResult": "results",
    "ParameterInfo": "results",
    "PlannerInfo": "results",
    "ReplanResult": "results",
    "PlanResult": "results",
    "RobotInfo": "results",
    "Trajectory": "trajectory",
}

__all__ = [
    "BenchmarkProgress", "BenchmarkResult", "BenchmarkRun", "CartesianResult", "ChaslesError", "Client", "ConfigSummary",
    "DEFAULT_TIMEOUT", "OptimizeResult", "ParameterInfo", "PlannerInfo", "PlanResult", "ReplanResult", "RobotInfo",
    "Trajectory",
]

if TYPE_CHECKING:
    from .benchmark import BenchmarkProgress, BenchmarkResult, BenchmarkRun, ConfigSummary
    from .client import DEFAULT_TIMEOUT, Client
    from .errors import ChaslesError
    from .results import CartesianResult, OptimizeResult, ParameterInfo, PlannerInfo, PlanResult, ReplanResult, RobotInfo
    from .trajectory import Trajectory


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted(list(globals()) + list(_EXPORTS))
