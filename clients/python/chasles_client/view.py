"""The 3-D viewer page of a result (``PlanResult.save_html`` / ``show``), written by the ``chasles``
CLI's ``view`` command (one implementation: the page the CLI and ``chasles-server --http-listen``
write). The CLI is found as ``$CHASLES_CLI``, then ``chasles`` on the PATH, then the repository's
``build/bin/chasles`` next to this package."""

from __future__ import annotations

import html
import os
import shutil
import subprocess
import tempfile
import webbrowser
from pathlib import Path
from typing import Any, Optional, Union

from google.protobuf import json_format
from google.protobuf.message import Message


def cli_path() -> str:
    """The ``chasles`` CLI that writes the page.

    Raises:
        FileNotFoundError: none was found (set CHASLES_CLI to its path).
    """
    explicit = os.environ.get("CHASLES_CLI")
    if explicit:
        return explicit
    found = shutil.which("chasles")
    if found:
        return found
    built = Path(__file__).resolve().parents[3] / "build" / "bin" / "chasles"
    if built.is_file():
        return str(built)
    raise FileNotFoundError("the chasles CLI writes the viewer page: set CHASLES_CLI to its path, put it on the PATH, "
                            "or build it (scripts/setup) into build/bin/")


def write_view(response: Message, request: Optional[Message], path: Union[str, os.PathLike]) -> Path:
    """Writes the viewer page of ``response`` (a PlanResponse, OptimizeResponse or
    CoordinateResponse) and the ``request`` it answers (robot and scene; None = the server's
    default robot and scene) to ``path`` (.html). Returns the path.

    Raises:
        RuntimeError: the CLI failed (its message says why).
    """
    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="chasles-view-") as tmp:
        files = []
        for name, message in (("response.json", response), ("request.json", request)):
            if message is None:
                continue
            file = Path(tmp) / name
            file.write_text(json_format.MessageToJson(message, preserving_proto_field_name=True), encoding="utf-8")
            files.append(str(file))
        done = subprocess.run([cli_path(), "view", *files, "--out", str(path)], capture_output=True, text=True,
                              check=False)
        if done.returncode != 0:
            raise RuntimeError(f"chasles view failed ({done.returncode}): {done.stderr.strip() or done.stdout.strip()}")
    return path


def show_view(response: Message, request: Optional[Message]) -> Any:
    """In a notebook: the page inline (an IPython HTML object holding an iframe); elsewhere the
    page opened in the browser (written to a temporary file, whose path is returned)."""
    with tempfile.NamedTemporaryFile(prefix="chasles-view-", suffix=".html", delete=False) as file:
        path = Path(file.name)
    write_view(response, request, path)
    try:
        from IPython import get_ipython  # noqa: PLC0415 (optional dependency)
        from IPython.display import HTML  # noqa: PLC0415
        if get_ipython() is not None:
            page = path.read_text(encoding="utf-8")
            return HTML(f'<iframe srcdoc="{html.escape(page, quote=True)}" style="width:100%;height:640px;border:0">'
                        "</iframe>")
    except ImportError:
        pass
    webbrowser.open(path.as_uri())
    return path
