"""Real servers on loopback for the replica tests and the replica benchmark: Debian's redis-server,
chasles-server replicas and nginx with deploy/nginx/nginx.conf, each bounded (it must be up within
30 s) and stopped by `LocalCluster.stop()` (SIGTERM, then SIGKILL after 10 s); every child also
gets SIGTERM when this process dies (PR_SET_PDEATHSIG).
"""
from __future__ import annotations

import re
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Callable, List, Optional

ROOT = Path(__file__).resolve().parents[2]
REDIS = "/usr/bin/redis-server"
NGINX = "/usr/sbin/nginx"
SETPRIV = "/usr/bin/setpriv"  # util-linux, Essential in Debian


def exits_with_this_process(args: List[str]) -> List[str]:
    """`args` run under util-linux's setpriv, which sets PR_SET_PDEATHSIG (SIGTERM when this
    process dies, even by SIGKILL) and execs them.

    Not a preexec_fn: with one, subprocess must fork(), and a fork while grpcio's threads run
    trips its fork handlers (grpc/grpc issue 31885: "assertion failed: state_ == State::kRunning"
    in thread_pool.cc, which aborted this suite once in CI). Without one, Python spawns the child
    with vfork/posix_spawn, which runs no fork handlers."""
    return [SETPRIV, "--pdeathsig", "TERM", "--", *args]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(("127.0.0.1", port)) == 0


def wait_for(predicate: Callable[[], bool], what: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise RuntimeError(f"{what} within {timeout} s")


class LocalCluster:
    """Processes started here, in one temporary directory."""

    def __init__(self, server_binary: str) -> None:
        for tool in (REDIS, NGINX):
            if not Path(tool).exists():
                raise RuntimeError(f"{tool} is missing: scripts/setup installs redis-server and nginx")
        self.binary = server_binary
        self._work = tempfile.TemporaryDirectory(prefix="chasles_cluster_")
        self.work = Path(self._work.name)
        self.processes: List[subprocess.Popen] = []
        self.replica_logs: List[Path] = []

    def spawn(self, args: List[str], log: Path) -> subprocess.Popen:
        with log.open("w") as out:
            process = subprocess.Popen(exits_with_this_process(args), stdout=out, stderr=out)
        self.processes.append(process)
        return process

    def start_redis(self) -> str:
        """A redis-server with its append-only file; returns its redis:// URL."""
        port = free_port()
        (self.work / "redis").mkdir(exist_ok=True)
        self.redis_port = port
        self.restart_redis()
        return f"redis://127.0.0.1:{port}"

    def restart_redis(self) -> subprocess.Popen:
        """(Re)starts redis-server on its port and directory: it reads its append-only file back.
        Every write is fsynced before Redis answers (appendfsync always)."""
        port = self.redis_port
        self.redis = self.spawn([REDIS, "--port", str(port), "--bind", "127.0.0.1", "--dir", str(self.work / "redis"),
                                 "--appendonly", "yes", "--appendfsync", "always", "--save", "",
                                 "--daemonize", "no"], self.work / "redis.log")
        wait_for(lambda: port_open(port), "redis-server did not listen")
        return self.redis

    def start_replica(self, store: Optional[str] = None, threads: int = 1) -> str:
        """A chasles-server on a free port (on `store` when given); returns host:port."""
        k = len(self.replica_logs)
        log = self.work / f"replica{k}.log"
        args = [self.binary, "--listen", "127.0.0.1:0", "--threads", str(threads)]
        if store:
            args += ["--store", store]
        self.spawn(args, log)
        self.replica_logs.append(log)
        found: List[str] = []

        def listening() -> bool:
            match = re.search(r"listening on \S+ \(port (\d+)\)", log.read_text())
            if match:
                found.append(match.group(1))
            return bool(match)

        wait_for(listening, f"replica {k} did not report its port")
        return f"127.0.0.1:{found[0]}"

    def start_nginx(self, replicas: List[str]) -> str:
        """nginx with deploy/nginx/nginx.conf, its upstream and listen ports rewritten; returns host:port."""
        conf = (ROOT / "deploy/nginx/nginx.conf").read_text()
        defaults = ["127.0.0.1:50051", "127.0.0.1:50052", "127.0.0.1:50053"]
        if len(replicas) != len(defaults):
            raise ValueError("deploy/nginx/nginx.conf balances three replicas")
        for default, actual in zip(defaults, replicas):
            conf = conf.replace(f"server {default};", f"server {actual};")
        port = free_port()
        conf = conf.replace("listen 127.0.0.1:8080 http2;", f"listen 127.0.0.1:{port} http2;")
        prefix = self.work / "nginx"
        (prefix / "logs").mkdir(parents=True, exist_ok=True)  # nginx opens logs/error.log before it reads -e
        (prefix / "nginx.conf").write_text(conf)
        self.spawn([NGINX, "-p", str(prefix), "-c", str(prefix / "nginx.conf"), "-e", "stderr",
                    "-g", "daemon off; pid nginx.pid;"], self.work / "nginx.log")
        wait_for(lambda: port_open(port), "nginx did not listen")
        return f"127.0.0.1:{port}"

    def stop(self) -> None:
        for process in reversed(self.processes):
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
        for process in reversed(self.processes):
            try:
                process.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        self.processes = []
        self._work.cleanup()
