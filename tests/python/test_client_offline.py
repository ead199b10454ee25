"""chasles_client without a server: conversions, trajectories, benchmark results, plots, errors."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import grpc
import numpy as np

from chasles.v1 import chasles_pb2 as pb
from chasles_client import BenchmarkResult, ChaslesError, Trajectory, convert
from chasles_client.plots import plot_benchmark, plot_trajectory
from chasles_client.results import limits_used

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def cubic_trajectory(n_samples: int = 21) -> pb.JointTrajectory:
    """Two joints on q = (t³, −2t²) over t in [0, 1]: exact velocities and accelerations."""
    message = pb.JointTrajectory(joint_names=["a", "b"])
    for t in np.linspace(0.0, 1.0, n_samples):
        message.points.add(time_from_start=t, positions=[t**3, -2 * t**2], velocities=[3 * t**2, -4 * t],
                           accelerations=[6 * t, -4.0])
    return message


class ConvertTest(unittest.TestCase):
    def test_plan_request_from_plain_data(self) -> None:
        request = convert.plan_request(
            np.array([0.0, 1.0]), [2.0, 3.0], "prm", {"range": 0.5, "max_nearest": 3, "star": True},
            scene={"boxes": [{"name": "b", "size": {"x": 1, "y": 1, "z": 1}}]}, time_budget=2, seed=np.int64(3),
            post_processing="collocation", max_velocity=[1.0, 2.0], collision_resolution=0.01)
        self.assertEqual(list(request.start.positions), [0.0, 1.0])
        self.assertEqual(list(request.goal.positions), [2.0, 3.0])
        self.assertEqual(request.planner.planner_id, "prm")
        self.assertEqual(request.planner.parameters["range"].double_value, 0.5)
        self.assertEqual(request.planner.parameters["max_nearest"].int_value, 3)
        self.assertTrue(request.planner.parameters["star"].bool_value)
        self.assertEqual(request.scene.boxes[0].size.x, 1.0)
        self.assertEqual(request.seed, 3)
        self.assertEqual(request.time_budget, 2.0)
        self.assertEqual(request.trajectory.post_processing, pb.TrajectoryOptions.COLLOCATION)
        self.assertEqual(list(request.trajectory.max_velocity), [1.0, 2.0])
        self.assertEqual(request.collision_resolution, 0.01)

    def test_nan_passes_through_for_the_server_to_check(self) -> None:
        request = convert.plan_request([math.nan, 0.0], [0.0, 0.0])
        self.assertTrue(math.isnan(request.start.positions[0]))
        request = convert.plan_request({"positions": ["NaN", 0.0]}, [0.0, 0.0])
        self.assertTrue(math.isnan(request.start.positions[0]))

    def test_pose_goal_from_dict(self) -> None:
        target, goal = convert.goal({"link": "tool", "pose": {"position": {"x": 0.5}}})
        self.assertEqual(target, "pose_goal")
        self.assertEqual(goal.pose.position.x, 0.5)
        self.assertEqual(convert.goal({"positions": [1.0], "tolerance": 0.01})[0], "goal")

    def test_pose_from_a_matrix_or_a_pair(self) -> None:
        # A rotation of 2.5 rad about a tilted axis (w small: the matrix's largest diagonal entry
        # leads); the quaternion is checked against its axis-angle definition.
        axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
        angle = 2.5
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        matrix = np.eye(4)
        matrix[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)  # Rodrigues
        matrix[:3, 3] = [0.1, 0.2, 0.3]
        pose = convert.pose_message(matrix)
        got = np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w])
        want = np.concatenate([math.sin(angle / 2) * axis, [math.cos(angle / 2)]])
        self.assertLess(min(np.abs(got - want).max(), np.abs(got + want).max()), 1e-12)
        self.assertEqual((pose.position.x, pose.position.y, pose.position.z), (0.1, 0.2, 0.3))
        pair = convert.pose_message(([1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]))
        self.assertEqual((pair.position.z, pair.orientation.w), (3.0, 1.0))
        with self.assertRaisesRegex(TypeError, "waypoints\\[2\\]: expected"):
            convert.pose_message(np.eye(3), "waypoints[2]")

    def test_unknown_fields_and_bad_types_name_the_field(self) -> None:
        with self.assertRaisesRegex(TypeError, "no field 'foo'"):
            convert.plan_request([0.0], [1.0], foo=3)
        with self.assertRaisesRegex(TypeError, "scene"):
            convert.plan_request([0.0], [1.0], scene={"boxs": []})
        with self.assertRaisesRegex(ValueError, "post_processing = 'fast'"):
            convert.plan_request([0.0], [1.0], post_processing="fast")
        with self.assertRaisesRegex(TypeError, r"parameters\['range'\]"):
            convert.planner_config("prm", {"range": "far"})
        with self.assertRaisesRegex(TypeError, "shape"):
            convert.joint_state([[0.0, 1.0]])

    def test_benchmark_request_from_plain_data(self) -> None:
        request = convert.benchmark_request(
            [{"name": "p", "start": [0.0, 0.0], "goal": [1.0, 1.0]}, pb.PlanRequest(seed=4)],
            ["rrt_connect", {"name": "prm_fast", "planner": "prm", "parameters": {"x": 1.5},
                             "post_processing": "spline"}], runs=2, run_budget=1.0, seed=9)
        self.assertEqual([p.name for p in request.problems], ["p", ""])
        self.assertEqual(list(request.problems[0].request.goal.positions), [1.0, 1.0])
        self.assertEqual(request.problems[1].request.seed, 4)
        self.assertEqual(request.configs[0].planner.planner_id, "rrt_connect")
        self.assertEqual(request.configs[1].name, "prm_fast")
        self.assertEqual(request.configs[1].planner.parameters["x"].double_value, 1.5)
        self.assertEqual(request.configs[1].trajectory.post_processing, pb.TrajectoryOptions.SPLINE)
        self.assertEqual((request.runs, request.run_budget, request.seed), (2, 1.0, 9))
        self.assertTrue(request.request_id.startswith("py-"))
        with self.assertRaisesRegex(TypeError, r"configs\[0\]: unknown keys \['planer'\]"):
            convert.benchmark_config({"planer": "prm"}, 0)

    def test_message_to_dict_keeps_ints_and_enum_names(self) -> None:
        stats = convert.message_to_dict(pb.PlannerStatistics(graph_states=2**40, path_length=1.5))
        self.assertEqual(stats["graph_states"], 2**40)
        self.assertIsInstance(stats["graph_states"], int)
        self.assertEqual(convert.message_to_dict(pb.BenchmarkRun(outcome=pb.SUCCESS))["outcome"], "SUCCESS")


    def test_plan_result_carries_the_repair(self) -> None:
        from chasles_client.results import PlanResult

        plain = PlanResult.from_response(pb.PlanResponse(outcome=pb.SUCCESS, duration=1.0, trajectory=cubic_trajectory()))
        self.assertIsNone(plain.repair)
        repaired = PlanResult.from_response(pb.PlanResponse(
            outcome=pb.SUCCESS, duration=1.0, trajectory=cubic_trajectory(),
            repair=pb.VerificationRepair(failure="collision at t = 0.5 s between link 'l2' and 'plate'",
                                         actions=["replanned 1 segment: verified"], repaired=True)))
        self.assertEqual(repaired.repair, {"failure": "collision at t = 0.5 s between link 'l2' and 'plate'",
                                           "actions": ["replanned 1 segment: verified"], "repaired": True})


class TrajectoryTest(unittest.TestCase):
    def test_arrays_from_message(self) -> None:
        traj = Trajectory.from_message(cubic_trajectory())
        self.assertEqual(traj.t.shape, (21,))
        for array in (traj.q, traj.qd, traj.qdd):
            self.assertEqual(array.shape, (21, 2))
        self.assertIsNone(traj.effort)
        self.assertEqual(traj.joint_names, ["a", "b"])
        self.assertEqual(traj.duration, 1.0)
        self.assertEqual(traj.q[-1].tolist(), [1.0, -2.0])

    def test_from_response_dict_and_round_trip(self) -> None:
        response = pb.PlanResponse(outcome=pb.SUCCESS, duration=1.0, trajectory=cubic_trajectory())
        from google.protobuf import json_format

        traj = Trajectory.from_response(json_format.MessageToDict(response))
        np.testing.assert_array_equal(traj.q, Trajectory.from_response(response).q)
        again = Trajectory.from_message(traj.to_message())
        np.testing.assert_array_equal(again.qdd, traj.qdd)

    def test_hermite_positions_exact_for_cubics(self) -> None:
        traj = Trajectory.from_message(cubic_trajectory(5))  # the cubic is exact between samples
        times = np.linspace(0.0, 1.0, 37)
        expected = np.stack([times**3, -2 * times**2], axis=1)
        np.testing.assert_allclose(traj.positions_at(times), expected, atol=1e-12)
        np.testing.assert_allclose(traj.positions_at(0.3), [0.027, -0.18], atol=1e-12)

    def test_write_csv(self) -> None:
        traj = Trajectory.from_message(cubic_trajectory())
        with tempfile.TemporaryDirectory() as directory:
            path = traj.write_csv(Path(directory) / "t.csv")
            with path.open() as stream:
                rows = list(csv.reader(stream))
        self.assertEqual(rows[0], ["t", "q_a", "q_b", "qd_a", "qd_b", "qdd_a", "qdd_b"])
        self.assertEqual(len(rows), 22)
        self.assertEqual(float(rows[-1][2]), -2.0)

    def test_limits_used_as_the_server(self) -> None:
        model = np.array([2.0, 3.0])
        v, a = limits_used(pb.TrajectoryOptions(max_velocity=[1.0, 5.0]), model)
        np.testing.assert_array_equal(v, [1.0, 3.0])  # capped at the model's
        np.testing.assert_array_equal(a, [2.0, 6.0])  # 2 × the velocity limits
        v, a = limits_used(pb.TrajectoryOptions(max_acceleration=[7.0, 8.0]), model)
        np.testing.assert_array_equal(v, model)
        np.testing.assert_array_equal(a, [7.0, 8.0])
        self.assertEqual(limits_used(None, None), (None, None))


def fake_benchmark_stream() -> "tuple[pb.BenchmarkRequest, list]":
    request = convert.benchmark_request([{"name": "table", "start": [0.0], "goal": [1.0]}],
                                        ["rrt_connect", "rrt_connect"], runs=2, request_id="b1")
    responses = []
    done = 0
    for config in range(2):
        for run in range(2):
            done += 1
            solved = not (config == 1 and run == 1)
            responses.append(pb.BenchmarkResponse(
                progress=pb.BenchmarkProgress(done=done, total=4, running=0, elapsed=0.1 * done, eta=-1),
                run=pb.BenchmarkRun(problem=0, config=config, run=run, seed=1 + run, solved=solved,
                                    outcome=pb.SUCCESS if solved else pb.NO_PATH_WITHIN_BUDGET,
                                    total_time=0.1 * (1 + config + run), path_length=2.0 if solved else 0.0,
                                    graph_states=100 * done)))
    responses.append(pb.BenchmarkResponse(progress=pb.BenchmarkProgress(done=4, total=4)))
    summary = pb.BenchmarkSummary(problem_names=["table"], config_names=["rrt_connect#0", "rrt_connect#1"],
                                  runs_finished=4, runs_total=4, wall_time=0.4, parallelism=2, request_id="b1")
    summary.configs.add(config=0, name="rrt_connect#0", runs=2, solved=2, success_rate=1.0)
    summary.configs.add(config=1, name="rrt_connect#1", runs=2, solved=1, success_rate=0.5)
    summary.logs.add(problem=0, name="table", ompl_log="Experiment chasles\n")
    responses.append(pb.BenchmarkResponse(progress=pb.BenchmarkProgress(done=4, total=4), summary=summary))
    return request, responses


class BenchmarkResultTest(unittest.TestCase):
    def test_from_stream(self) -> None:
        request, responses = fake_benchmark_stream()
        progress, runs = [], []
        result = BenchmarkResult.from_stream(iter(responses), request, on_progress=progress.append,
                                             on_run=runs.append)
        self.assertEqual(len(progress), 6)
        self.assertEqual(len(runs), 4)
        self.assertEqual(result.config_names, ["rrt_connect#0", "rrt_connect#1"])
        self.assertEqual({r.config_name for r in result.runs}, {"rrt_connect#0", "rrt_connect#1"})
        self.assertEqual(result.summary["rrt_connect#1"].solved, 1)
        array = result.to_array()
        self.assertEqual(array.shape, (4,))
        self.assertEqual(int(array["solved"].sum()), 3)
        self.assertEqual(array["graph_states"].dtype, np.uint64)
        self.assertEqual(result.columns()["outcome"][3], "NO_PATH_WITHIN_BUDGET")
        np.testing.assert_allclose(result.times_by_config()["rrt_connect#1"], [0.2, 0.3])
        self.assertEqual(result.success_rates(), {"rrt_connect#0": 1.0, "rrt_connect#1": 0.5})

    def test_default_names_before_a_summary(self) -> None:
        request, responses = fake_benchmark_stream()
        result = BenchmarkResult.from_stream(iter(responses[:-1]), request)
        self.assertEqual(result.config_names, ["rrt_connect#0", "rrt_connect#1"])
        self.assertEqual(result.runs_finished, 4)

    def test_files(self) -> None:
        request, responses = fake_benchmark_stream()
        result = BenchmarkResult.from_stream(iter(responses), request)
        with tempfile.TemporaryDirectory() as directory:
            logs = result.write_ompl_logs(Path(directory) / "logs")
            self.assertEqual([p.name for p in logs], ["table.log"])
            self.assertEqual(logs[0].read_text(), "Experiment chasles\n")
            with result.write_csv(Path(directory) / "runs.csv").open() as stream:
                rows = list(csv.DictReader(stream))
            self.assertEqual(len(rows), 4)
            self.assertEqual(rows[0]["config_name"], "rrt_connect#0")
            data = json.loads(result.write_json(Path(directory) / "r.json").read_text())
            self.assertEqual(len(data["runs"]), 4)
            self.assertEqual(data["summaries"][1]["success_rate"], 0.5)


class PlotTest(unittest.TestCase):
    def test_trajectory_png_and_svg(self) -> None:
        traj = Trajectory.from_message(cubic_trajectory())
        with tempfile.TemporaryDirectory() as directory:
            png = Path(directory) / "t.png"
            figure = plot_trajectory(traj, velocity_limits=[3.0, 4.0], acceleration_limits=[6.0, 6.0], path=png)
            self.assertEqual(len(figure.axes), 3)
            data = png.read_bytes()
            self.assertTrue(data.startswith(PNG_SIGNATURE))
            self.assertGreater(len(data), 1024)
            svg = Path(directory) / "t.svg"
            plot_trajectory(traj, path=svg)
            self.assertIn("<svg", svg.read_text())
            with self.assertRaisesRegex(ValueError, "extension"):
                plot_trajectory(traj, path=Path(directory) / "t.bmp")

    def test_benchmark_png(self) -> None:
        request, responses = fake_benchmark_stream()
        result = BenchmarkResult.from_stream(iter(responses), request)
        with tempfile.TemporaryDirectory() as directory:
            png = Path(directory) / "b.png"
            figure = plot_benchmark(result, path=png)
            self.assertEqual(len(figure.axes), 2)
            self.assertTrue(png.read_bytes().startswith(PNG_SIGNATURE))


class FakeRpcError(grpc.RpcError, grpc.Call):
    """An RpcError as the stubs raise it (only code() and details() are used)."""

    def code(self) -> grpc.StatusCode:
        return grpc.StatusCode.NOT_FOUND

    def details(self) -> str:
        return "unknown planner 'x'"

    def initial_metadata(self):  # noqa: ANN201 - grpc.Call interface
        return ()

    def trailing_metadata(self):  # noqa: ANN201
        return ()

    def is_active(self) -> bool:
        return False

    def time_remaining(self):  # noqa: ANN201
        return None

    def cancel(self) -> bool:
        return False

    def add_callback(self, callback) -> bool:  # noqa: ANN001
        return False


class ErrorAndCliTest(unittest.TestCase):
    def test_error_carries_code_and_message(self) -> None:
        error = ChaslesError.from_rpc_error(FakeRpcError(), "Plan")
        self.assertEqual(error.code, grpc.StatusCode.NOT_FOUND)
        self.assertEqual(error.code_name, "NOT_FOUND")
        self.assertEqual(error.message, "unknown planner 'x'")
        self.assertEqual(str(error), "Plan: NOT_FOUND: unknown planner 'x'")

    def test_cli_help(self) -> None:
        done = subprocess.run([sys.executable, "-m", "chasles_client", "--help"], capture_output=True, text=True,
                              timeout=60)
        self.assertEqual(done.returncode, 0, done.stderr)
        for command in ("health", "planners", "plan", "optimize", "bench"):
            self.assertIn(command, done.stdout)


if __name__ == "__main__":
    unittest.main()
