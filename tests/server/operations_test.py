"""chasles-server as an operator runs it: server reflection (list and call the service the way
grpcurl does, from descriptors the server sends), and request logs that hostile clients cannot
forge, colour or flood (text and JSON lines). Starts CHASLES_SERVER_BIN on 127.0.0.1:0 itself.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import tempfile
import time
import unittest
from pathlib import Path

import grpc
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from chasles.v1 import chasles_pb2, chasles_pb2_grpc

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = json.loads((ROOT / "examples/requests/panda_table.json").read_text())


def _exits_with_this_process(args: list) -> list:
    """PR_SET_PDEATHSIG through util-linux's setpriv rather than a preexec_fn: a preexec_fn makes
    subprocess fork(), and a fork while grpcio's threads run can abort in its fork handlers
    (grpc/grpc issue 31885; tests/python/local_cluster.py says more)."""
    return ["/usr/bin/setpriv", "--pdeathsig", "TERM", "--", *args]


class Server:
    """A chasles-server on a free loopback port with its stderr in a file."""

    def __init__(self, *flags: str) -> None:
        binary = os.environ.get("CHASLES_SERVER_BIN")
        if not binary:
            raise unittest.SkipTest("CHASLES_SERVER_BIN is not set (ctest sets it)")
        self.dir = tempfile.TemporaryDirectory(prefix="chasles_operations_")
        self.log = Path(self.dir.name) / "server.log"
        with self.log.open("wb") as log:
            self.process = subprocess.Popen(_exits_with_this_process([binary, "--listen", "127.0.0.1:0", "--threads", "2",
                                                                      *flags]), stdout=log, stderr=log)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            match = re.search(rb"listening on \S+ \(port (\d+)\)", self.log.read_bytes())
            if match:
                self.address = f"127.0.0.1:{int(match.group(1))}"
                self.channel = grpc.insecure_channel(self.address)
                return
            if self.process.poll() is not None:
                raise RuntimeError("chasles-server exited: " + self.log.read_text(errors="replace"))
            time.sleep(0.05)
        self.stop()
        raise RuntimeError("chasles-server did not report its port")

    def lines_after_startup(self) -> list[bytes]:
        return [line for line in self.log.read_bytes().split(b"\n")
                if line and b"listening on" not in line and b"security:" not in line]

    def wait_for_lines(self, count: int) -> list[bytes]:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            lines = self.lines_after_startup()
            if len(lines) >= count:
                return lines
            time.sleep(0.02)
        return self.lines_after_startup()

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.dir.cleanup()


def _reflection_classes():
    """grpc.reflection.v1alpha messages, declared from the published protocol's field numbers
    (no generated code of ours is involved)."""
    T = descriptor_pb2.FieldDescriptorProto
    f = descriptor_pb2.FileDescriptorProto(name="operations_test/reflection.proto",
                                           package="grpc.reflection.v1alpha", syntax="proto3")

    def message(name, *fields):
        m = f.message_type.add(name=name)
        for field_name, number, kind, type_name, repeated in fields:
            field = m.field.add(name=field_name, number=number, type=kind,
                                label=T.LABEL_REPEATED if repeated else T.LABEL_OPTIONAL)
            if type_name:
                field.type_name = ".grpc.reflection.v1alpha." + type_name

    message("ServerReflectionRequest", ("host", 1, T.TYPE_STRING, None, False),
            ("file_by_filename", 3, T.TYPE_STRING, None, False),
            ("file_containing_symbol", 4, T.TYPE_STRING, None, False),
            ("list_services", 7, T.TYPE_STRING, None, False))
    message("FileDescriptorResponse", ("file_descriptor_proto", 1, T.TYPE_BYTES, None, True))
    message("ServiceResponse", ("name", 1, T.TYPE_STRING, None, False))
    message("ListServiceResponse", ("service", 1, T.TYPE_MESSAGE, "ServiceResponse", True))
    message("ErrorResponse", ("error_code", 1, T.TYPE_INT32, None, False),
            ("error_message", 2, T.TYPE_STRING, None, False))
    message("ServerReflectionResponse", ("valid_host", 1, T.TYPE_STRING, None, False),
            ("file_descriptor_response", 4, T.TYPE_MESSAGE, "FileDescriptorResponse", False),
            ("list_services_response", 6, T.TYPE_MESSAGE, "ListServiceResponse", False),
            ("error_response", 7, T.TYPE_MESSAGE, "ErrorResponse", False))
    pool = descriptor_pool.DescriptorPool()
    pool.Add(f)
    get = message_factory.GetMessageClass if hasattr(message_factory, "GetMessageClass") else \
        message_factory.MessageFactory(pool).GetPrototype
    return (get(pool.FindMessageTypeByName("grpc.reflection.v1alpha.ServerReflectionRequest")),
            get(pool.FindMessageTypeByName("grpc.reflection.v1alpha.ServerReflectionResponse")))


class ReflectionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.server = Server("--quiet")
        cls.Request, cls.Response = _reflection_classes()
        cls.call = cls.server.channel.stream_stream(
            "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
            request_serializer=lambda m: m.SerializeToString(),
            response_deserializer=cls.Response.FromString)

    @classmethod
    def tearDownClass(cls) -> None:
        cls.server.channel.close()
        cls.server.stop()

    def ask(self, **fields):
        return next(iter(self.call(iter([self.Request(**fields)]), timeout=30)))

    def test_lists_the_services(self) -> None:
        names = {s.name for s in self.ask(list_services="*").list_services_response.service}
        self.assertIn("chasles.v1.Planning", names)
        self.assertIn("grpc.health.v1.Health", names)

    def test_calls_a_method_from_the_descriptors_it_sends(self) -> None:
        # Fetch the file that defines the service, and its dependencies, as grpcurl does.
        pool = descriptor_pool.DescriptorPool()
        added = set()
        files = []
        response = self.ask(file_containing_symbol="chasles.v1.Planning")
        self.assertFalse(response.HasField("error_response"), response.error_response.error_message)
        for blob in response.file_descriptor_response.file_descriptor_proto:
            files.append(descriptor_pb2.FileDescriptorProto.FromString(blob))
        by_name = {f.name: f for f in files}
        pending = ["-"]
        while pending:
            pending = [d for f in by_name.values() for d in f.dependency if d not in by_name]
            for name in pending:
                reply = self.ask(file_by_filename=name)
                for blob in reply.file_descriptor_response.file_descriptor_proto:
                    proto = descriptor_pb2.FileDescriptorProto.FromString(blob)
                    by_name[proto.name] = proto

        def add(name: str) -> None:
            if name in added:
                return
            for dependency in by_name[name].dependency:
                add(dependency)
            pool.Add(by_name[name])
            added.add(name)

        for name in list(by_name):
            add(name)
        service = pool.FindServiceByName("chasles.v1.Planning")
        self.assertIn("Plan", [m.name for m in service.methods])
        method = service.FindMethodByName("ListPlanners")
        get = message_factory.GetMessageClass if hasattr(message_factory, "GetMessageClass") else \
            message_factory.MessageFactory(pool).GetPrototype
        request_class, response_class = get(method.input_type), get(method.output_type)
        call = self.server.channel.unary_unary("/chasles.v1.Planning/ListPlanners",
                                               request_serializer=lambda m: m.SerializeToString(),
                                               response_deserializer=response_class.FromString)
        planners = call(request_class(), timeout=30)
        ids = [p.id for p in planners.planners]
        self.assertIn("rrt_connect", ids)


class MalformedMessageTest(unittest.TestCase):
    """Bytes that are not the method's message: INVALID_ARGUMENT naming the type, streams too."""

    @classmethod
    def setUpClass(cls) -> None:
        cls.server = Server("--quiet")

    @classmethod
    def tearDownClass(cls) -> None:
        cls.server.channel.close()
        cls.server.stop()

    def test_benchmark_stream(self) -> None:
        call = self.server.channel.unary_stream("/chasles.v1.Planning/Benchmark")
        with self.assertRaises(grpc.RpcError) as refused:
            list(call(b"\xff\xff\xff\xff\x0f not a protobuf", timeout=30))
        self.assertEqual(refused.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("is not a valid chasles.v1.BenchmarkRequest message", refused.exception.details())

    def test_unary_and_then_served(self) -> None:
        call = self.server.channel.unary_unary("/chasles.v1.Planning/Optimize")
        with self.assertRaises(grpc.RpcError) as refused:
            call(b"\x0a\xff\xff", timeout=30)
        self.assertEqual(refused.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("is not a valid chasles.v1.OptimizeRequest message (3 bytes", refused.exception.details())
        stub = chasles_pb2_grpc.PlanningStub(self.server.channel)
        self.assertEqual(stub.Plan(_plan_request("after"), timeout=60).outcome, chasles_pb2.SUCCESS)


def _plan_request(request_id: str, planner: str = "rrt_connect") -> chasles_pb2.PlanRequest:
    request = chasles_pb2.PlanRequest()
    request.start.positions.extend(EXAMPLE["start"]["positions"])
    request.goal.positions.extend(EXAMPLE["goal"]["positions"])
    request.planner.planner_id = planner
    request.request_id = request_id
    return request


HOSTILE_ID = "ok\nchasles-server: Plan request=forged status=OK\x1b[31mred\x1b[0m" + "A" * (1 << 20)


class RequestLogTest(unittest.TestCase):
    def run_requests(self, *flags: str) -> tuple[Server, list[bytes], grpc.RpcError]:
        server = Server(*flags)
        self.addCleanup(server.stop)
        stub = chasles_pb2_grpc.PlanningStub(server.channel)
        stub.Plan(_plan_request(HOSTILE_ID), timeout=60)
        with self.assertRaises(grpc.RpcError) as refused:
            stub.Plan(_plan_request("nul", planner="rrt\0connect"), timeout=60)
        lines = server.wait_for_lines(2)
        server.channel.close()
        return server, lines, refused.exception

    def check_common(self, lines: list[bytes], error: grpc.RpcError) -> None:
        self.assertEqual(len(lines), 2, lines)  # one line per call: nothing forged
        for line in lines:
            self.assertNotIn(b"\x1b", line)
            self.assertNotIn(b"\0", line)
            self.assertLess(len(line), 4000)
        # The NUL does not cut the client's message short: the list of known planners follows it.
        self.assertEqual(error.code(), grpc.StatusCode.NOT_FOUND, error.details())
        self.assertIn("rrt\\x00connect", error.details())
        self.assertIn("rrt_connect", error.details().split("rrt\\x00connect", 1)[1])

    def test_text_lines(self) -> None:
        _, lines, error = self.run_requests()
        self.check_common(lines, error)
        self.assertTrue(lines[0].startswith(b'chasles-server: Plan request="ok\\nchasles-server: Plan request=forged '
                                            b'status=OK\\x1b[31mred\\x1b[0mAAAA'), lines[0][:200])
        self.assertIn(b"status=OK outcome=SUCCESS", lines[0])
        self.assertRegex(lines[0], rb" client=ipv4:127\.0\.0\.1:\d+ ")
        self.assertIn(b"status=NOT_FOUND", lines[1])

    def test_json_lines(self) -> None:
        _, lines, error = self.run_requests("--log-format", "json", "--log-field-max", "64")
        self.check_common(lines, error)
        first, second = (json.loads(line) for line in lines)
        self.assertEqual(first["rpc"], "Plan")
        self.assertEqual(first["status"], "OK")
        self.assertEqual(first["outcome"], "SUCCESS")
        self.assertTrue(first["request_id"].startswith("ok\nchasles-server: Plan request=forged status=OK\x1b[31m"))
        self.assertLess(len(first["request_id"]), 100)
        self.assertEqual(set(first["stages_ms"]), {"validate", "plan", "shortcut", "parameterize", "optimize", "verify"})
        self.assertGreater(first["total_ms"], 0)
        self.assertEqual(second["status"], "NOT_FOUND")
        self.assertIn("rrt\\x00connect", second["message"])


if __name__ == "__main__":
    unittest.main()
