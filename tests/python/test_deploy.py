"""The deployment files (issue 15, item 5) checked as far as this machine can: they parse, nginx
accepts its config (nginx -t), every flag they pass to chasles-server is one the built server
knows, and the compose file's services are the set tests/python/test_replicas.py runs (Redis, three
replicas on the shared store at the ports of deploy/nginx/nginx.conf, nginx with that file).
"""
from __future__ import annotations

import os
import re
import subprocess
import tempfile
import unittest
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
DEPLOY = ROOT / "deploy"


def _flags(args):
    return [a for a in args if a.startswith("--")]


class DeploymentFiles(unittest.TestCase):
    def server_help(self) -> str:
        binary = os.environ.get("CHASLES_SERVER_BIN")
        if not binary:
            raise unittest.SkipTest("CHASLES_SERVER_BIN is not set")
        return subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=30).stdout

    def test_nginx_accepts_its_config(self) -> None:
        with tempfile.TemporaryDirectory() as prefix:
            (Path(prefix) / "logs").mkdir()
            done = subprocess.run(["/usr/sbin/nginx", "-t", "-p", prefix, "-c", str(DEPLOY / "nginx/nginx.conf"),
                                   "-e", "stderr", "-g", "pid nginx.pid;"], capture_output=True, text=True, timeout=30)
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertIn("syntax is ok", done.stderr)

    def test_compose_runs_the_tested_set(self) -> None:
        compose = yaml.safe_load((DEPLOY / "compose.yaml").read_text())
        services = compose["services"]
        self.assertEqual(sorted(services), ["chasles1", "chasles2", "chasles3", "nginx", "redis"])
        redis_port = services["redis"]["command"][services["redis"]["command"].index("--port") + 1]
        upstream = re.findall(r"server (127\.0\.0\.1:\d+);", (DEPLOY / "nginx/nginx.conf").read_text())
        listens = []
        known = self.server_help()
        for name in ("chasles1", "chasles2", "chasles3"):
            args = services[name]["command"]
            listens.append(args[args.index("--listen") + 1])
            self.assertEqual(args[args.index("--store") + 1], f"redis://127.0.0.1:{redis_port}")
            for flag in _flags(args):
                self.assertIn(flag, known, f"{name}: chasles-server does not know {flag}")
        self.assertEqual(listens, upstream)
        self.assertIn("./nginx/nginx.conf:/etc/chasles/nginx.conf:ro", services["nginx"]["volumes"])
        self.assertEqual(services["chasles1"]["build"]["dockerfile"], "deploy/Dockerfile")

    def test_kubernetes_manifests(self) -> None:
        documents = []
        for path in sorted((DEPLOY / "k8s").glob("*.yaml")):
            documents += [d for d in yaml.safe_load_all(path.read_text()) if d]
        kinds = sorted(d["kind"] for d in documents)
        self.assertEqual(kinds, ["Deployment", "HorizontalPodAutoscaler", "Service", "Service", "Service",
                                 "StatefulSet"])
        by = {(d["kind"], d["metadata"]["name"]): d for d in documents}
        deployment = by[("Deployment", "chasles")]
        pod = deployment["spec"]["template"]["spec"]
        container = pod["containers"][0]
        port = container["ports"][0]["containerPort"]
        self.assertEqual(container["readinessProbe"]["grpc"]["port"], port)
        self.assertEqual(container["livenessProbe"]["grpc"]["port"], port)
        args = container["args"]
        for flag in _flags(args):
            self.assertIn(flag, self.server_help(), f"chasles-server does not know {flag}")
        redis = by[("Service", "chasles-redis")]
        self.assertEqual(args[args.index("--store") + 1], f"redis://chasles-redis:{redis['spec']['ports'][0]['port']}")
        self.assertGreater(pod["terminationGracePeriodSeconds"], float(args[args.index("--shutdown-grace") + 1]))
        self.assertEqual(by[("Service", "chasles-headless")]["spec"]["clusterIP"], "None")
        for name in ("chasles", "chasles-headless"):
            self.assertEqual(by[("Service", name)]["spec"]["selector"], deployment["spec"]["selector"]["matchLabels"])
        hpa = by[("HorizontalPodAutoscaler", "chasles")]
        self.assertEqual(hpa["spec"]["scaleTargetRef"]["name"], "chasles")
        self.assertEqual(hpa["spec"]["metrics"][0]["resource"]["name"], "cpu")

    def test_dockerfile_builds_with_the_setup_script(self) -> None:
        text = (DEPLOY / "Dockerfile").read_text()
        self.assertRegex(text, r"(?m)^FROM debian:12$")
        self.assertRegex(text, r"(?m)^RUN .*scripts/setup")
        self.assertIn('ENTRYPOINT ["/usr/local/bin/chasles-server"]', text)


if __name__ == "__main__":
    unittest.main()
