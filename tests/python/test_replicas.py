"""Several replicas behind a proxy (issue 15, item 2b): a real redis-server, three chasles-server
replicas on the shared store and Debian's nginx started with deploy/nginx/nginx.conf (its ports
rewritten to free ones), all on loopback, bounded and cleaned up. Plans go through nginx and are
spread over the replicas; a trajectory committed on one replica is a conflict on another.
"""
from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
import unittest
from pathlib import Path
from typing import List

import grpc

from chasles_client import ChaslesError, Client
from chasles_client._stubs import pb

sys.path.insert(0, str(Path(__file__).resolve().parent))
from local_cluster import ROOT, LocalCluster  # noqa: E402


class ReplicasBehindNginx(unittest.TestCase):
    cluster: LocalCluster

    @classmethod
    def setUpClass(cls) -> None:
        binary = os.environ.get("CHASLES_SERVER_BIN")
        if not binary:
            raise unittest.SkipTest("CHASLES_SERVER_BIN is not set (ctest sets it to the built chasles-server)")
        cls.cluster = LocalCluster(binary)
        try:
            store = cls.cluster.start_redis()
            cls.replicas = [cls.cluster.start_replica(store) for _ in range(3)]
            cls.logs = cls.cluster.replica_logs
            cls.proxy = cls.cluster.start_nginx(cls.replicas)
        except BaseException:
            cls.cluster.stop()
            raise

    @classmethod
    def tearDownClass(cls) -> None:
        cls.cluster.stop()

    def test_plans_through_nginx_spread_over_the_replicas(self) -> None:
        before = [log.read_text().count("Plan request") for log in self.logs]
        with Client(self.proxy, timeout=60.0) as client:
            robot_id = client.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf")
            example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
            results = [client.plan(example["start"]["positions"], example["goal"]["positions"], robot_id=robot_id,
                                   time_budget=2.0, seed=s) for s in range(1, 10)]
            self.assertTrue(all(r.success for r in results), [r.message for r in results])
        served = [log.read_text().count("Plan request") - b for log, b in zip(self.logs, before)]
        # nginx balances round-robin; every replica resolved the robot id from the shared store.
        self.assertGreaterEqual(sum(1 for n in served if n > 0), 2, served)
        self.assertEqual(sum(served), 9, served)

    def test_a_commit_on_one_replica_is_a_conflict_on_another(self) -> None:
        first, second = Client(self.replicas[0], timeout=60.0), Client(self.replicas[1], timeout=60.0)
        with first, second:
            robot_id = first.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf")
            example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
            planned = first.plan(example["start"]["positions"], example["goal"]["positions"], robot_id=robot_id,
                                 time_budget=2.0)
            self.assertTrue(planned.success, planned.message)
            first.stub.CreateWorkcell(pb.CreateWorkcellRequest(name="proxy_cell"), timeout=30)
            commit = pb.CommitTrajectoryRequest(workcell="proxy_cell", robot_name="left", robot_id=robot_id,
                                                trajectory=planned.trajectory.to_message(), start_time=4.0e9,
                                                hold=600.0)
            first.stub.CommitTrajectory(commit, timeout=30)
            commit.robot_name = "right"
            with self.assertRaises(grpc.RpcError) as raised:
                second.stub.CommitTrajectory(commit, timeout=30)
            self.assertEqual(raised.exception.code(), grpc.StatusCode.FAILED_PRECONDITION)
            self.assertIn("conflicts with a committed one", raised.exception.details())
        # And through the proxy, whichever replica answers.
        with Client(self.proxy, timeout=60.0) as proxied:
            created = proxied.stub.CreateWorkcell(pb.CreateWorkcellRequest(name="proxy_cell"), timeout=30)
            self.assertFalse(created.created)
            self.assertEqual(created.active_reservations, 1)


class ReplicaFailures(unittest.TestCase):
    """Replicas that stop: SIGTERM drains (in-flight calls finish, new ones are refused, health
    says NOT_SERVING), SIGKILL under load costs no call of a client balancing over the others."""

    def setUp(self) -> None:
        binary = os.environ.get("CHASLES_SERVER_BIN")
        if not binary:
            raise unittest.SkipTest("CHASLES_SERVER_BIN is not set")
        self.cluster = LocalCluster(binary)

    def tearDown(self) -> None:
        self.cluster.stop()

    def test_sigterm_finishes_the_call_in_flight_and_refuses_new_ones(self) -> None:
        address = self.cluster.start_replica(threads=2)
        example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
        with Client(address, timeout=30.0, retries=2) as client:
            client.wait_until_serving(timeout=20.0)
            outcome: List[object] = []

            def long_plan() -> None:  # RRT* uses its whole budget
                outcome.append(client.plan(example["start"]["positions"], example["goal"]["positions"],
                                           planner="rrt_star", time_budget=1.2))

            worker = threading.Thread(target=long_plan)
            worker.start()
            time.sleep(0.4)
            stopped_at = time.monotonic()
            self.cluster.processes[0].send_signal(signal.SIGTERM)
            time.sleep(0.2)
            # Draining: health says so, and a new call is refused as UNAVAILABLE (a balancing
            # client would retry it on another replica) ...
            self.assertEqual(client.health(timeout=5.0), "NOT_SERVING")
            with self.assertRaises(ChaslesError) as refused:
                client.planners(timeout=5.0)
            self.assertIn("UNAVAILABLE", str(refused.exception))
            self.assertIn("shutting down", str(refused.exception))
            # ... while the call in flight finishes with its answer.
            worker.join(timeout=30.0)
            self.assertTrue(outcome and outcome[0].success, outcome)
            self.cluster.processes[0].wait(timeout=15.0)
            self.assertLess(time.monotonic() - stopped_at, 10.0)  # --shutdown-grace (10 s by default)

    def test_killed_replica_and_redis_lose_nothing(self) -> None:
        # SIGKILL a replica right after its commit, then Redis; Redis restarted from its
        # append-only file and a new replica: the robot, workcell and reservation are all there.
        store = self.cluster.start_redis()
        first = self.cluster.start_replica(store, threads=2)
        example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
        with Client(first, timeout=60.0) as client:
            robot_id = client.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf")
            planned = client.plan(example["start"]["positions"], example["goal"]["positions"], robot_id=robot_id)
            client.stub.CreateWorkcell(pb.CreateWorkcellRequest(name="survivor"), timeout=30)
            client.stub.CommitTrajectory(pb.CommitTrajectoryRequest(
                workcell="survivor", robot_name="left", robot_id=robot_id,
                trajectory=planned.trajectory.to_message(), start_time=4.0e9, hold=600.0), timeout=30)
        replica = self.cluster.processes[-1]
        replica.kill()
        replica.wait()
        self.cluster.redis.kill()
        self.cluster.redis.wait()
        self.cluster.restart_redis()
        second = self.cluster.start_replica(store, threads=2)
        with Client(second, timeout=60.0) as client:
            created = client.stub.CreateWorkcell(pb.CreateWorkcellRequest(name="survivor"), timeout=30)
            self.assertFalse(created.created)
            self.assertEqual(created.active_reservations, 1)
            again = client.plan(example["start"]["positions"], example["goal"]["positions"], robot_id=robot_id)
            self.assertTrue(again.success, again.message)

    def test_a_replica_killed_under_load_costs_no_call(self) -> None:
        addresses = [self.cluster.start_replica(threads=2) for _ in range(3)]
        example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
        failures: List[str] = []
        done = [0]
        lock = threading.Lock()
        stop = time.monotonic() + 4.0
        with Client(",".join(addresses), timeout=30.0) as client:
            client.wait_until_serving(timeout=20.0)

            def load(seed: int) -> None:
                while time.monotonic() < stop:
                    try:
                        result = client.plan(example["start"]["positions"], example["goal"]["positions"],
                                             time_budget=1.0, seed=seed)
                        ok = result.success
                        why = result.message
                    except Exception as error:  # noqa: BLE001 - every failure counts
                        ok, why = False, str(error)
                    with lock:
                        done[0] += 1
                        if not ok:
                            failures.append(why)
                    seed += 4

            threads = [threading.Thread(target=load, args=(s,)) for s in range(1, 5)]
            for t in threads:
                t.start()
            time.sleep(1.5)
            self.cluster.processes[1].kill()  # SIGKILL, mid-call for some of the threads
            for t in threads:
                t.join(timeout=60.0)
        self.assertEqual(failures, [])
        self.assertGreater(done[0], 20)


class BenchmarkFanOut(unittest.TestCase):
    """A client of several replicas spreads a benchmark's runs over them (issue 15, item 4) and
    merges the answers: the same runs as one server makes, the same summaries, one OMPL log."""

    def test_two_replicas_give_the_runs_one_server_gives(self) -> None:
        binary = os.environ.get("CHASLES_SERVER_BIN")
        if not binary:
            raise unittest.SkipTest("CHASLES_SERVER_BIN is not set")
        cluster = LocalCluster(binary)
        try:
            replicas = [cluster.start_replica(threads=1) for _ in range(2)]
            problem = json.loads((ROOT / "examples/requests/planar_2r_table.json").read_text())
            problem["name"] = "table"
            kwargs = dict(problems=[problem], configs=["rrt_connect", "rrt"], runs=5, run_budget=1.5, seed=5)
            with Client(replicas[0], timeout=60.0) as one:
                single = one.benchmark(**kwargs)
            seen = []
            with Client(",".join(replicas), timeout=60.0) as both:
                shared = both.benchmark(**kwargs, on_run=lambda r: seen.append(r.run))
        finally:
            cluster.stop()

        def key(result):
            return sorted((r.config, r.run, r.seed, r.outcome, r.solved, r.path_length) for r in result.runs)

        self.assertEqual(len(shared.runs), 10)
        self.assertEqual(key(shared), key(single))
        self.assertEqual(sorted(seen), sorted(r.run for r in single.runs))
        for a, b in zip(shared.summaries, single.summaries):
            self.assertEqual((a.name, a.runs, a.solved, a.median_length), (b.name, b.runs, b.solved, b.median_length))
        log = shared.ompl_logs["table"]
        self.assertIn("\n5 runs per planner\n", log)
        self.assertEqual(log.count("\n5 runs\n"), 2)
        self.assertEqual(len(log.splitlines()), len(single.ompl_logs["table"].splitlines()))


if __name__ == "__main__":
    unittest.main()
