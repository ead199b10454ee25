"""The one exception type of the client: a failed RPC with its gRPC status."""

from __future__ import annotations

from typing import Optional

import grpc


class ChaslesError(Exception):
    """An RPC failed: the server's status code and message (or a local validation error).

    Attributes:
        code: the gRPC status code (e.g. ``grpc.StatusCode.INVALID_ARGUMENT``).
        message: the server's message, e.g. ``start.positions[0] = nan must be finite``.
        method: the RPC that failed (``"Plan"``), or ``""``.
    """

    def __init__(self, code: grpc.StatusCode, message: str, method: str = "") -> None:
        self.code = code
        self.message = message
        self.method = method
        prefix = f"{method}: " if method else ""
        super().__init__(f"{prefix}{code.name}: {message}")

    @property
    def code_name(self) -> str:
        """The status code's name, e.g. ``"INVALID_ARGUMENT"``."""
        return self.code.name

    @classmethod
    def from_rpc_error(cls, error: grpc.RpcError, method: str = "") -> "ChaslesError":
        """Wraps a ``grpc.RpcError`` raised by a stub call."""
        code: Optional[grpc.StatusCode] = None
        details = ""
        if isinstance(error, grpc.Call):
            code = error.code()
            details = error.details() or ""
        return cls(code or grpc.StatusCode.UNKNOWN, details or str(error), method)

