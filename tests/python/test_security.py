"""chasles_client over TLS, mutual TLS and bearer tokens against a chasles-server this test starts.

Certificates come from scripts/make-test-certs (openssl) in a temporary directory; the server
(CHASLES_SERVER_BIN) runs with --tls-cert/--tls-key/--tls-client-ca/--tokens for the whole module.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path
from typing import List, Optional

import grpc

from chasles_client import ChaslesError, Client
from chasles_client._stubs import pb

sys.path.insert(0, str(Path(__file__).resolve().parent))
from local_cluster import exits_with_this_process  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PLAN_TOKEN = "py-plan-token-3c9d0e61a7b2"
COMMIT_TOKEN = "py-commit-token-b81f4d2e95c0"
EXAMPLE = json.loads((ROOT / "examples/requests/panda_table.json").read_text())

_server: Optional[subprocess.Popen] = None
_workdir: Optional[tempfile.TemporaryDirectory] = None
_certs = Path()
_address = ""


def setUpModule() -> None:  # noqa: N802 - unittest's name
    global _server, _workdir, _certs, _address
    binary = os.environ.get("CHASLES_SERVER_BIN")
    if not binary:
        raise unittest.SkipTest("CHASLES_SERVER_BIN is not set (ctest sets it to the built chasles-server)")
    _workdir = tempfile.TemporaryDirectory(prefix="chasles_python_tls_")
    _certs = Path(_workdir.name) / "certs"
    subprocess.run([str(ROOT / "scripts/make-test-certs"), str(_certs)], check=True, capture_output=True)
    tokens = _certs / "tokens.txt"
    tokens.write_text(f"# NAME ROLE TOKEN\nplanner plan {PLAN_TOKEN}\noperator commit {COMMIT_TOKEN}\n")
    log_path = Path(_workdir.name) / "server.log"
    with log_path.open("w") as log:
        _server = subprocess.Popen(
            exits_with_this_process(
                [binary, "--listen", "127.0.0.1:0", "--threads", "2", "--tls-cert", str(_certs / "server.pem"),
                 "--tls-key", str(_certs / "server.key"), "--tls-client-ca", str(_certs / "ca.pem"),
                 "--tokens", str(tokens)]),
            stdout=log, stderr=log)
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:
        match = re.search(r"listening on \S+ \(port (\d+)\)", log_path.read_text())
        if match:
            _address = f"localhost:{match.group(1)}"
            return
        if _server.poll() is not None:
            text = log_path.read_text()
            tearDownModule()
            raise RuntimeError(f"chasles-server exited with {_server.returncode if _server else '?'}:\n{text}")
        time.sleep(0.05)
    text = log_path.read_text()
    tearDownModule()
    raise RuntimeError(f"chasles-server did not report its port within 30 s:\n{text}")


def tearDownModule() -> None:  # noqa: N802
    global _server
    if _server is not None and _server.poll() is None:
        _server.send_signal(signal.SIGTERM)
        try:
            _server.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            _server.kill()
            _server.wait()
    _server = None
    if _workdir is not None:
        _workdir.cleanup()


def _client(token: Optional[str] = None, cert: str = "client") -> Client:
    return Client(_address, timeout=30.0, tls_ca=_certs / "ca.pem", tls_cert=_certs / f"{cert}.pem",
                  tls_key=_certs / f"{cert}.key", token=token)


class SecurityTest(unittest.TestCase):
    def test_health_needs_no_token(self) -> None:
        with _client() as client:
            self.assertEqual(client.health(), "SERVING")

    def test_tokens_and_roles(self) -> None:
        with _client() as client:
            with self.assertRaises(ChaslesError) as raised:
                client.planners()
            self.assertEqual(raised.exception.code, grpc.StatusCode.UNAUTHENTICATED)
            self.assertIn("missing 'authorization: Bearer <token>' metadata", raised.exception.message)
        with _client("wrong-token-0000000000") as client:
            with self.assertRaises(ChaslesError) as raised:
                client.planners()
            self.assertEqual(raised.exception.code, grpc.StatusCode.UNAUTHENTICATED)
            self.assertIn("unknown token", raised.exception.message)
        with _client(PLAN_TOKEN) as client:
            self.assertGreater(len(client.planners()), 0)
            result = client.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"])
            self.assertTrue(result.success, result.message)
            with self.assertRaises(grpc.RpcError) as denied:
                client.stub.CreateWorkcell(pb.CreateWorkcellRequest(name="cell"), timeout=10)
            self.assertEqual(denied.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
            self.assertIn("needs a token with role 'commit'", denied.exception.details())

    def test_untrusted_client_certificate_is_refused(self) -> None:
        with _client(PLAN_TOKEN, cert="other-client") as client:
            with self.assertRaises(ChaslesError) as raised:
                client.planners(timeout=5)
            self.assertEqual(raised.exception.code, grpc.StatusCode.UNAVAILABLE)

    def test_command_line(self) -> None:
        tls = ["--server", _address, "--tls-ca", str(_certs / "ca.pem"), "--tls-cert", str(_certs / "client.pem"),
               "--tls-key", str(_certs / "client.key")]

        def run(arguments: List[str], token: Optional[str] = None) -> subprocess.CompletedProcess:
            env = dict(os.environ)
            env.pop("CHASLES_TOKEN", None)
            if token:
                env["CHASLES_TOKEN"] = token
            return subprocess.run([sys.executable, "-m", "chasles_client", *tls, *arguments], env=env,
                                  capture_output=True, text=True, timeout=120)

        done = run(["planners"], token=PLAN_TOKEN)
        self.assertEqual(done.returncode, 0, done.stderr)
        done = run(["--token", PLAN_TOKEN, "plan", str(ROOT / "examples/requests/panda_table.json")])
        self.assertEqual(done.returncode, 0, done.stderr)
        token_file = _certs / "token.txt"
        token_file.write_text(COMMIT_TOKEN + "\n")
        done = run(["--token-file", str(token_file), "planners"])
        self.assertEqual(done.returncode, 0, done.stderr)
        done = run(["planners"])
        self.assertEqual(done.returncode, 1, done.stderr)
        self.assertIn("UNAUTHENTICATED", done.stderr)


if __name__ == "__main__":
    unittest.main()
