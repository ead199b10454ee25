"""chasles_client end to end against a chasles-server this test starts (CHASLES_SERVER_BIN).

The server listens on 127.0.0.1:0 and prints the port it got; it runs for the whole module and
is stopped (SIGTERM, then SIGKILL after 10 s) at the end.
"""

from __future__ import annotations

import csv
import json
import math
import os
import queue
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path
from typing import Optional

import grpc
import numpy as np

from chasles_client import BenchmarkRun, ChaslesError, Client, Trajectory
from chasles_client._stubs import pb
from chasles_client.plots import plot_benchmark, plot_trajectory

sys.path.insert(0, str(Path(__file__).resolve().parent))
from local_cluster import LocalCluster, exits_with_this_process  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
EXAMPLE = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
START = np.array(EXAMPLE["start"]["positions"])
GOAL = np.array(EXAMPLE["goal"]["positions"])

_server: Optional[subprocess.Popen] = None
_server_log: Optional[Path] = None
_address = ""
_workdir: Optional[tempfile.TemporaryDirectory] = None


def setUpModule() -> None:  # noqa: N802 - unittest's name
    global _server, _server_log, _address, _workdir
    binary = os.environ.get("CHASLES_SERVER_BIN")
    if not binary:
        raise unittest.SkipTest("CHASLES_SERVER_BIN is not set (ctest sets it to the built chasles-server)")
    _workdir = tempfile.TemporaryDirectory(prefix="chasles_python_test_")
    _server_log = Path(_workdir.name) / "server.log"
    with _server_log.open("w") as log:
        _server = subprocess.Popen(exits_with_this_process([binary, "--listen", "127.0.0.1:0", "--threads", "2"]),
                                   stdout=log, stderr=log)
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:
        match = re.search(r"listening on \S+ \(port (\d+)\)", _server_log.read_text())
        if match:
            _address = f"127.0.0.1:{match.group(1)}"
            break
        if _server.poll() is not None:
            code, log = _server.returncode, _server_log.read_text()
            tearDownModule()
            raise RuntimeError(f"chasles-server exited with {code}:\n{log}")
        time.sleep(0.05)
    else:
        log = _server_log.read_text()
        tearDownModule()
        raise RuntimeError(f"chasles-server did not report its port within 30 s:\n{log}")


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


class ServerTest(unittest.TestCase):
    client: Client
    robot_id: str

    @classmethod
    def setUpClass(cls) -> None:
        cls.client = Client(_address, timeout=60.0)
        cls.client.wait_until_serving(timeout=20.0)
        # The server's default robot is this URDF and SRDF under the name "panda".
        cls.robot_id = cls.client.upload_robot(ROOT / "examples/robots/panda.urdf",
                                               ROOT / "examples/robots/panda.srdf", name="panda")
        cls.out = Path(tempfile.mkdtemp(prefix="plots_", dir=_workdir.name))

    @classmethod
    def tearDownClass(cls) -> None:
        cls.client.close()

    def check_trajectory(self, traj, start: np.ndarray, goal: np.ndarray,
                         velocity_limits: np.ndarray, acceleration_limits: np.ndarray) -> None:
        n = len(start)
        samples = len(traj)
        self.assertGreater(samples, 2)
        self.assertEqual(traj.t.shape, (samples,))
        for array in (traj.q, traj.qd, traj.qdd):
            self.assertEqual(array.shape, (samples, n))
            self.assertTrue(np.isfinite(array).all())
        self.assertEqual(len(traj.joint_names), n)
        self.assertEqual(traj.t[0], 0.0)
        self.assertTrue((np.diff(traj.t) > 0).all(), "sample times must increase")
        self.assertAlmostEqual(traj.duration, traj.t[-1], delta=1e-9)
        np.testing.assert_allclose(traj.q[0], start, atol=1e-6, rtol=0)
        np.testing.assert_allclose(traj.q[-1], goal, atol=1e-6, rtol=0)
        self.assertTrue((np.abs(traj.qd) <= velocity_limits * (1 + 1e-9) + 1e-9).all(),
                        f"peak |qd| {np.abs(traj.qd).max(axis=0)} above {velocity_limits}")
        self.assertTrue((np.abs(traj.qdd) <= acceleration_limits * (1 + 1e-9) + 1e-9).all(),
                        f"peak |qdd| {np.abs(traj.qdd).max(axis=0)} above {acceleration_limits}")

    def test_health(self) -> None:
        self.assertEqual(self.client.health(), "SERVING")
        self.assertEqual(self.client.health("chasles.v1.Planning"), "SERVING")
        with self.assertRaises(ChaslesError) as caught:
            self.client.health("no.such.Service")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)

    def test_planners(self) -> None:
        planners = {p.id: p for p in self.client.planners()}
        self.assertIn("rrt_connect", planners)
        rrt = planners["rrt_connect"]
        self.assertIn("arm", rrt.robot_kinds)
        for parameter in rrt.parameters:
            self.assertIn(parameter.type, ("double", "int", "bool"))
            self.assertLessEqual(parameter.min, parameter.default)
            self.assertLessEqual(parameter.default, parameter.max)

    def test_upload_robot_answers_its_limits(self) -> None:
        info = self.client.robot_info(self.robot_id)
        self.assertEqual(len(info.joint_names), 7)
        self.assertEqual(info.velocity_limits.shape, (7,))
        self.assertTrue((info.velocity_limits > 0).all())
        self.assertTrue((info.lower_limits < info.upper_limits).all())
        self.assertEqual(info.collision_model, {"kind": "shapes"})  # spheres already: nothing fitted

    def test_a_mesh_robot_is_fitted_with_spheres_unless_exact_meshes(self) -> None:
        robots = ROOT / "examples/robots"
        meshes = {f"package://ur5_meshes/{p.name}": p for p in sorted((robots / "ur5_meshes").glob("*.stl"))}
        fitted = self.client.upload_robot(robots / "ur5_meshes.urdf", robots / "ur5_meshes.srdf", meshes)
        model = self.client.robot_info(fitted).collision_model
        self.assertEqual(model["kind"], "fitted_spheres")
        self.assertEqual(model["shapes_fitted"], 7)
        self.assertGreater(model["spheres"], 7)
        self.assertGreater(model["reach"], 0.0)
        exact = self.client.upload_robot(robots / "ur5_meshes.urdf", robots / "ur5_meshes.srdf", meshes,
                                         exact_meshes=True)
        self.assertNotEqual(exact, fitted)
        self.assertEqual(self.client.robot_info(exact).collision_model, {"kind": "shapes"})

    def test_plan_on_the_default_robot(self) -> None:
        result = self.client.plan(START, GOAL, time_budget=3.0, seed=7, request_id="python-default")
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        self.assertEqual(result.outcome, "SUCCESS")
        self.assertEqual(result.request_id, "python-default")
        # The default robot is examples/robots/panda.urdf: the same content hash as the upload, so
        # the client knows the limits the trajectory was timed with.
        self.assertEqual(result.robot_id, self.robot_id)
        model = self.client.robot_info(self.robot_id).velocity_limits
        np.testing.assert_array_equal(result.velocity_limits, model)
        np.testing.assert_array_equal(result.acceleration_limits, 2 * model)
        self.check_trajectory(result.trajectory, START, GOAL, result.velocity_limits, result.acceleration_limits)
        self.assertEqual(result.path.shape[1], 7)
        np.testing.assert_allclose(result.path[0], START, atol=1e-9)
        np.testing.assert_allclose(result.path[-1], GOAL, atol=1e-9)
        self.assertGreater(result.statistics["path_length"], 0.0)
        self.assertIsInstance(result.statistics["collision_checks"], int)
        self.assertLessEqual(result.quality["max_velocity_ratio"], 1.0 + 1e-9)
        self.assertGreater(result.timings["total"], 0.0)

        png = self.out / "default.png"
        plot_trajectory(result, path=png)
        data = png.read_bytes()
        self.assertTrue(data.startswith(PNG_SIGNATURE))
        self.assertGreater(len(data), 1024)
        svg = self.out / "default.svg"
        plot_trajectory(result.trajectory, result.velocity_limits, result.acceleration_limits, path=svg)
        self.assertIn("<svg", svg.read_text())

    def test_limits_come_with_the_response(self) -> None:
        # A fresh client knows no robot: the limits are the response's own (TrajectoryLimits).
        fresh = Client(self.client.address)
        result = fresh.plan(START, GOAL, time_budget=3.0, seed=7, max_velocity=[1.0] * 7)
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        np.testing.assert_array_equal(result.velocity_limits, np.full(7, 1.0))
        np.testing.assert_array_equal(result.acceleration_limits, np.full(7, 2.0))
        self.check_trajectory(result.trajectory, START, GOAL, result.velocity_limits, result.acceleration_limits)

    def test_plan_with_lower_limits_and_an_uploaded_scene(self) -> None:
        scene = json.loads((ROOT / "examples/scenes/table.json").read_text())
        scene["boxes"].append({"name": "post", "size": {"x": 0.05, "y": 0.05, "z": 0.3},
                               "pose": {"position": {"x": -0.6, "y": 0.6, "z": 0.15}}})
        scene_id = self.client.upload_scene(scene)
        self.assertTrue(scene_id)
        velocity = np.array([1.0, 1.0, 1.0, 1.0, 1.5, 1.5, 1.5])
        result = self.client.plan(START, GOAL, robot_id=self.robot_id, scene_id=scene_id, time_budget=3.0,
                                  seed=3, max_velocity=velocity, sample_period=0.02)
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        self.assertEqual(result.scene_id, scene_id)
        np.testing.assert_array_equal(result.velocity_limits, velocity)
        self.check_trajectory(result.trajectory, START, GOAL, velocity, 2 * velocity)
        self.assertLessEqual(np.diff(result.trajectory.t).max(), 0.02 + 1e-9)

    def test_nan_start_is_invalid_argument_naming_the_field(self) -> None:
        start = START.copy()
        start[2] = math.nan
        with self.assertRaises(ChaslesError) as caught:
            self.client.plan(start, GOAL)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertEqual(caught.exception.method, "Plan")
        self.assertIn("start.positions[2]", caught.exception.message)

    def test_unknown_planner_and_scene_are_not_found(self) -> None:
        with self.assertRaises(ChaslesError) as caught:
            self.client.plan(START, GOAL, planner="no_such_planner")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("rrt_connect", caught.exception.message)  # the known names are listed
        with self.assertRaises(ChaslesError) as caught:
            self.client.plan(START, GOAL, scene_id="0123456789abcdef")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)

    def test_optimize_a_short_path(self) -> None:
        path = np.array([START, START + [0.2, 0.1, 0.0, 0.1, 0.0, 0.0, 0.0], START + [0.3, 0.2, 0.0, 0.2, 0.0, 0.1, 0.0]])
        result = self.client.optimize(path, robot_id=self.robot_id, post_processing="topp")
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        self.assertEqual(result.optimizer["used"], "topp")
        model = self.client.robot_info(self.robot_id).velocity_limits
        self.check_trajectory(result.trajectory, path[0], path[-1], model, 2 * model)
        # A timed trajectory goes back in as the input path.
        again = self.client.optimize(result.trajectory, robot_id=self.robot_id, post_processing="none")
        self.assertTrue(again.success, f"{again.outcome}: {again.message}")
        self.assertGreater(again.input_duration, 0.0)

    def test_cartesian_path_along_a_line_and_stopped_by_a_wall(self) -> None:
        example = json.loads((ROOT / "examples/requests/cartesian_panda_table.json").read_text(encoding="utf-8"))
        result = self.client.cartesian_path_request(example)
        self.assertTrue(result.success, f"{result.stop}: {result.message}")
        self.assertEqual(result.fraction, 1.0)
        self.assertEqual(result.path.shape, (result.steps + 1, 7))
        self.assertLess(result.trajectory_line_deviation, 2e-3)
        self.assertGreater(result.trajectory.duration, 0.0)
        # The same first line through the keyword call, its pose as a 4x4 matrix; a wall across it
        # three quarters along stops the path there.
        first = example["waypoints"][0]
        corner = np.eye(4)
        corner[:3, :3] = np.diag([1.0, -1.0, -1.0])  # the example's tool points down (x = 1, w = 0)
        corner[:3, 3] = [first["position"]["x"], first["position"]["y"], first["position"]["z"]]
        wall = {"boxes": [{"name": "wall", "size": {"x": 0.3, "y": 0.02, "z": 0.3},
                           "pose": {"position": {"x": corner[0, 3], "y": 0.15, "z": corner[2, 3]}}}]}
        carried = self.client.cartesian_path(START, [corner], "panda_tcp", attached_objects=[
            {"name": "pen", "link": "panda_tcp", "touch_links": ["panda_hand"],
             "capsules": [{"radius": 0.01, "length": 0.1}]}])
        self.assertTrue(carried.complete, f"{carried.stop}: {carried.message}")
        self.assertTrue(any("('pen'): covered by" in w for w in carried.warnings), carried.warnings)
        stopped = self.client.cartesian_path(START, [corner], "panda_tcp", scene=wall)
        self.assertEqual(stopped.stop, "COLLISION", stopped.message)
        self.assertGreater(stopped.fraction, 0.0)
        self.assertLess(stopped.fraction, 1.0)
        self.assertIsNotNone(stopped.timed)
        with self.assertRaises(ChaslesError) as raised:
            self.client.cartesian_path(START, [corner], "panda_tcp", max_step=-1.0)
        self.assertIn("max_step = -1", str(raised.exception))

    def test_plan_carrying_a_rod(self) -> None:
        example = json.loads((ROOT / "examples/requests/panda_carry_rod.json").read_text(encoding="utf-8"))
        result = self.client.plan_request(example)
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        self.assertTrue(any("('rod'): covered by" in w for w in result.response.warnings), result.response.warnings)
        # The keyword call, the rod as plain data: a start with the rod in the block collides.
        start = list(example["start"]["positions"])
        start[0] = 0.0
        blocked = self.client.plan(start, example["goal"]["positions"], scene=example["scene"],
                                   attached_objects=example["attachedObjects"])
        self.assertEqual(blocked.outcome, "START_IN_COLLISION", blocked.message)
        self.assertIn("'rod'", blocked.message)

    def test_plan_keeping_a_glass_upright(self) -> None:
        example = json.loads((ROOT / "examples/requests/panda_shelf_glass.json").read_text(encoding="utf-8"))
        result = self.client.plan_request(example)
        self.assertTrue(result.success, f"{result.outcome}: {result.message}")
        self.assertGreater(result.quality["max_constraint_ratio"], 0.0)
        self.assertLessEqual(result.quality["max_constraint_ratio"], 1.0)
        # The keyword call, the constraint as plain data: a start with the hand turned breaks it.
        start = list(example["start"]["positions"])
        start[6] += 0.3
        broken = self.client.plan(start, example["goal"]["positions"], scene=example["scene"],
                                  path_constraints=example["pathConstraints"])
        self.assertEqual(broken.outcome, "START_VIOLATES_CONSTRAINTS", broken.message)
        self.assertIn("path_constraints.orientation[0]", broken.message)

    def test_plan_around_people_walking_by_and_replan(self) -> None:
        example = json.loads((ROOT / "examples/requests/base_crossing_people.json").read_text(encoding="utf-8"))
        walkers = example["movingObstacles"]

        def clearance(result, offset: float = 0.0) -> float:
            # The base's two body spheres (r 0.2 at ±0.15 m along its heading) against each walker
            # (an upright cylinder, r 0.3, walking linearly between its waypoints), every sample.
            traj = result.trajectory
            closest = np.inf
            for t, q in zip(traj.t, traj.q):
                for walker in walkers:
                    times = [w["time"] for w in walker["waypoints"]]
                    xs = [w["pose"]["position"]["x"] for w in walker["waypoints"]]
                    ys = [w["pose"]["position"]["y"] for w in walker["waypoints"]]
                    centre = np.array([np.interp(t + offset, times, xs), np.interp(t + offset, times, ys)])
                    for along in (0.15, -0.15):
                        body = q[:2] + along * np.array([np.cos(q[2]), np.sin(q[2])])
                        closest = min(closest, np.linalg.norm(body - centre) - 0.5)
            return closest

        for method in ("SPACE_TIME", "VELOCITY_OBSTACLES"):
            result = self.client.plan(example["start"]["positions"], example["goal"]["positions"],
                                      robot=example["robot"], scene=example["scene"], sample_period=0.005,
                                      moving_obstacles=walkers, moving_obstacle_method=method)
            self.assertTrue(result.success, f"{method}: {result.outcome}: {result.message}")
            self.assertGreater(clearance(result), 0.0, method)
        blind = self.client.plan(example["start"]["positions"], example["goal"]["positions"], robot=example["robot"],
                                 scene=example["scene"], sample_period=0.005)
        self.assertLess(clearance(blind), 0.0)
        # The stream: kept while nothing changes, replanned round a walker seen at t = 1 s.
        problem = dict(example, movingObstacles=[])
        answers = list(self.client.replan([{"plan": problem}, {"time": 0.5},
                                           {"time": 1.0, "moving_obstacles_changed": True,
                                            "moving_obstacles": walkers[:1]}]))
        self.assertEqual([a.action for a in answers], ["PLANNED", "KEPT", "REPLANNED"])
        self.assertIn("walker_a", answers[2].reason)
        self.assertTrue(answers[2].plan.success, answers[2].plan.message)
        walkers = walkers[:1]
        self.assertGreater(clearance(answers[2].plan, offset=1.0), 0.0)

    def test_save_a_plan_as_a_viewer_page(self) -> None:
        example = json.loads((ROOT / "examples/requests/panda_shelf.json").read_text(encoding="utf-8"))
        result = self.client.plan_request(example)
        self.assertTrue(result.success, result.message)
        with tempfile.TemporaryDirectory() as tmp:
            page = result.save_html(Path(tmp) / "view.html")
            text = page.read_text(encoding="utf-8")
            self.assertIn("const CHASLES_VIEW = {", text)
            self.assertIn("shelf_board", text)       # the request's scene, not the default table
            self.assertIn('var REVISION="111"', text)  # three.js inlined: the page needs no network
            self.assertNotIn('src="http', text)

    def test_coordinate_a_fleet_and_sample_its_knots(self) -> None:
        request = ROOT / "examples/requests/coordinate_fleet.json"
        response = self.client.coordinate(str(request))
        self.assertEqual(response.outcome, pb.SUCCESS, response.message)
        self.assertEqual(response.method, "fleet")
        goals = json.loads(request.read_text())["robots"]
        self.assertEqual(len(response.robots), len(goals))
        for robot, asked in zip(response.robots, goals):
            traj = Trajectory.from_knots(robot.knots, period=0.05)
            # Limits: 1 m/s per coordinate (the disc base's), acceleration 2 m/s² by default.
            self.check_trajectory(traj, np.array(asked["start"]["positions"]), np.array(asked["goal"]["positions"]),
                                  np.array([1.0, 1.0, 1.0]), np.array([2.0, 2.0, 2.0]))

    def test_fleet_session_answers_goals_as_they_come(self) -> None:
        request = ROOT / "examples/requests/coordinate_fleet.json"
        opened = self.client.open_fleet_session("py-depot", str(request))
        robots = json.loads(request.read_text())["robots"]
        self.assertEqual(opened.robots, len(robots))
        first = {r["name"]: r["goal"]["positions"] for r in robots[:10]}
        response = self.client.assign_fleet_goals("py-depot", first, now=opened.start_time)
        self.assertEqual([r.robot for r in response.results], list(first))
        # A goal behind a node another robot of the batch is bound for waits until that robot is idle.
        deferred = {}
        for result in response.results:
            if result.outcome != pb.SUCCESS:
                self.assertIn("is going to park", result.message)
                deferred[result.robot] = first[result.robot]
        self.assertLess(len(deferred), len(first))
        plans = list(response.plans)
        if deferred:
            idle = max(plan.finish_time for plan in plans) + 1.0
            again = self.client.assign_fleet_goals("py-depot", deferred, now=idle)
            for result in again.results:
                self.assertEqual(result.outcome, pb.SUCCESS, result.message)
                for robot in result.moved_aside:  # idle at its goal, it stepped aside
                    first.pop(robot, None)
            plans += list(again.plans)
        ends = {}
        for plan in plans:  # in order: a robot's later plan replaces its earlier one
            ends[plan.robot] = Trajectory.from_knots(plan.knots, period=0.05).q[-1]
        for robot, goal in first.items():
            np.testing.assert_allclose(ends[robot][:2], goal[:2], atol=1e-9)
        with self.assertRaises(ChaslesError) as raised:
            self.client.assign_fleet_goals("py-depot", {"nobody": [0.5, 0.5, 0.0]})
        self.assertIn("goals[0].robot = 'nobody'", str(raised.exception))
        self.assertTrue(self.client.close_fleet_session("py-depot"))
        self.assertFalse(self.client.close_fleet_session("py-depot"))

    def test_fleet_stream_carries_states_and_goals(self) -> None:
        request = ROOT / "examples/requests/coordinate_fleet.json"
        opened = self.client.open_fleet_session("py-stream", str(request))
        robots = json.loads(request.read_text())["robots"]
        outbox: "queue.Queue[Optional[dict]]" = queue.Queue()

        def messages():
            while (item := outbox.get()) is not None:
                yield item

        answers = self.client.stream_fleet_session(messages(), timeout=60)
        t0 = opened.start_time
        outbox.put({"name": "py-stream", "now": t0, "goals": {r["name"]: r["goal"]["positions"] for r in robots[:10]}})
        first = next(answers)
        self.assertEqual(len(first.results), 10)
        # A robot still moving 2 s in reports where its plan had it at 1.5 s: LATE by 0.5 s.
        late = None
        for plan in first.plans:
            traj = Trajectory.from_knots(plan.knots, period=0.01)
            seen, now = t0 + 1.5 - plan.start_time, t0 + 2.0 - plan.start_time
            i, j = int(round(seen / 0.01)), int(round(now / 0.01))
            if 0 < i and j < len(traj.t) and np.linalg.norm(traj.qd[i][:2]) > 0.05 and np.linalg.norm(traj.qd[j][:2]) > 0.05:
                late = (plan.robot, traj.q[i][:2])
                break
        self.assertIsNotNone(late)
        outbox.put({"now": t0 + 2.0, "states": {late[0]: late[1]}})
        second = next(answers)
        self.assertEqual(second.states[0].robot, late[0])
        self.assertEqual(second.states[0].status, pb.LATE, second.states[0].message)
        # (Session times are seconds since the epoch, about 1.8e9: they resolve 2.4e-7 s.)
        self.assertAlmostEqual(second.states[0].delay, 0.5, delta=1e-5)
        self.assertIn(late[0], [plan.robot for plan in second.plans])
        # A bad message ends the stream with an error naming it.
        outbox.put({"now": t0 + 3.0, "states": {"nobody": (0.0, 0.0)}})
        with self.assertRaises(ChaslesError) as raised:
            next(answers)
        self.assertIn("message 2: states[0].robot = 'nobody'", str(raised.exception))
        outbox.put(None)
        self.assertTrue(self.client.close_fleet_session("py-stream"))

    def test_several_replicas_balanced_and_one_killed_costs_no_call(self) -> None:
        # Two more replicas; the client balances over all three and retries UNAVAILABLE.
        cluster = LocalCluster(os.environ["CHASLES_SERVER_BIN"])
        try:
            extra = [cluster.start_replica(threads=1) for _ in range(2)]
            with Client(",".join([_address] + extra), timeout=30.0) as client:
                client.wait_until_serving(timeout=20.0)
                for _ in range(6):
                    self.assertTrue(client.planners())
                # Round-robin: every replica answered some of them.
                for log in cluster.replica_logs:
                    self.assertIn("ListPlanners request", log.read_text())
                cluster.processes[0].kill()  # SIGKILL: its connections break
                cluster.processes[0].wait()
                results = [client.plan(START, GOAL, planner="rrt_connect", time_budget=2.0, seed=s)
                           for s in range(1, 13)]
                self.assertTrue(all(r.success for r in results), [r.message for r in results])
        finally:
            cluster.stop()

    def test_cli_plan_writes_a_plot(self) -> None:
        png = self.out / "cli.png"
        done = subprocess.run([sys.executable, "-m", "chasles_client", "--server", _address, "plan",
                               str(ROOT / "examples/requests/panda_table.json"), "--plot", str(png)],
                              capture_output=True, text=True, timeout=60)
        self.assertEqual(done.returncode, 0, done.stdout + done.stderr)
        self.assertIn("SUCCESS", done.stdout)
        self.assertTrue(png.read_bytes().startswith(PNG_SIGNATURE))

    def test_example_script(self) -> None:
        svg = self.out / "example.svg"
        done = subprocess.run([sys.executable, str(ROOT / "examples/python/plan_and_plot.py"), "--server", _address,
                               "--out", str(svg)], capture_output=True, text=True, timeout=60)
        self.assertEqual(done.returncode, 0, done.stdout + done.stderr)
        self.assertIn("<svg", svg.read_text())


class BenchmarkTest(unittest.TestCase):
    """Benchmark RPC: 2 configurations × 1 problem × 2 runs."""

    client: Client

    @classmethod
    def setUpClass(cls) -> None:
        cls.client = Client(_address, timeout=60.0)
        cls.client.wait_until_serving(timeout=20.0)

    @classmethod
    def tearDownClass(cls) -> None:
        cls.client.close()

    def test_benchmark(self) -> None:
        progress, runs = [], []
        problem = {"name": "panda_table", "start": START.tolist(), "goal": GOAL.tolist()}
        configs = ["rrt_connect", {"name": "rrt_connect_short", "planner": "rrt_connect",
                                   "parameters": {"range": 0.5}}]
        result = self.client.benchmark([problem], configs, runs=2, run_budget=2.0, parallelism=2, seed=5,
                                       on_progress=progress.append, on_run=runs.append, timeout=60.0)
        self.assertEqual(len(runs), 4)
        self.assertTrue(all(isinstance(r, BenchmarkRun) for r in runs))
        self.assertGreaterEqual(len(progress), 4)
        self.assertEqual(progress[-1].done, 4)
        self.assertEqual(progress[-1].total, 4)
        self.assertEqual((result.runs_finished, result.runs_total, result.stopped), (4, 4, False))
        self.assertEqual(result.problem_names, ["panda_table"])
        self.assertEqual(result.config_names, ["rrt_connect", "rrt_connect_short"])
        self.assertEqual(sorted((r.config, r.run) for r in result.runs), [(0, 0), (0, 1), (1, 0), (1, 1)])
        self.assertEqual({r.seed for r in result.runs}, {5, 6})
        self.assertEqual([s.runs for s in result.summaries], [2, 2])
        for summary in result.summaries:
            self.assertEqual(summary.success_rate, summary.solved / summary.runs)
        array = result.to_array()
        self.assertEqual(array.shape, (4,))
        self.assertTrue(array["solved"].all(), result.runs)
        self.assertTrue((array["path_length"] > 0).all())

        out = Path(tempfile.mkdtemp(prefix="bench_", dir=_workdir.name))
        logs = result.write_ompl_logs(out)
        self.assertEqual([p.name for p in logs], ["panda_table.log"])
        text = logs[0].read_text()
        self.assertIn("rrt_connect_short", text)
        with result.write_csv(out / "runs.csv").open() as stream:
            self.assertEqual(len(list(csv.DictReader(stream))), 4)
        self.assertEqual(len(json.loads(result.write_json(out / "runs.json").read_text())["runs"]), 4)
        png = out / "bench.png"
        plot_benchmark(result, path=png)
        self.assertTrue(png.read_bytes().startswith(PNG_SIGNATURE))
        self.assertGreater(png.stat().st_size, 1024)
        svg = out / "bench.svg"
        plot_benchmark(result, path=svg)
        self.assertIn("<svg", svg.read_text())

    def test_stop_benchmark_keeps_the_finished_runs(self) -> None:
        stops = []

        def stop_after_first_run(run: BenchmarkRun) -> None:
            if not stops:  # the request id is known before the call: stop it from the callback
                stops.append(self.client.stop_benchmark("python-stop-test"))

        problem = {"start": START.tolist(), "goal": GOAL.tolist()}
        result = self.client.benchmark([problem], ["rrt_connect"], runs=1000, run_budget=1.0, parallelism=1,
                                       request_id="python-stop-test", on_run=stop_after_first_run, timeout=60.0)
        self.assertEqual(stops, [True])
        self.assertTrue(result.stopped)
        self.assertEqual(result.request_id, "python-stop-test")
        self.assertEqual(result.runs_total, 1000)
        self.assertGreaterEqual(result.runs_finished, 1)
        self.assertLess(result.runs_finished, 1000)
        self.assertEqual(len(result.runs), result.runs_finished)
        self.assertEqual(result.summaries[0].runs, result.runs_finished)

    def test_stop_unknown_benchmark_is_not_found(self) -> None:
        with self.assertRaises(ChaslesError) as caught:
            self.client.stop_benchmark("no-such-benchmark")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no-such-benchmark", caught.exception.message)

    def test_bad_benchmark_request_is_invalid_argument(self) -> None:
        with self.assertRaises(ChaslesError) as caught:
            self.client.benchmark([{"start": START.tolist(), "goal": GOAL.tolist()}], ["rrt_connect"], runs=20000)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertEqual(caught.exception.method, "Benchmark")
        self.assertIn("runs", caught.exception.message)


if __name__ == "__main__":
    unittest.main()
