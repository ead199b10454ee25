"""The generated chasles.v1 modules, imported once with a helpful error when they are missing."""

from __future__ import annotations

try:
    from chasles.v1 import chasles_pb2 as pb
    from chasles.v1 import chasles_pb2_grpc as pb_grpc
except ImportError as error:  # pragma: no cover - depends on the environment
    raise ImportError(
        "chasles_client needs the generated stubs chasles.v1.chasles_pb2 / chasles_pb2_grpc: "
        "build them with `cmake --build build --target chasles_python_stubs` and put build/python "
        "on PYTHONPATH (PYTHONPATH=build/python:clients/python /usr/bin/python3 ...)"
    ) from error

__all__ = ["pb", "pb_grpc"]
