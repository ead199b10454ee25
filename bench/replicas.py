#!/usr/bin/python3
"""Several replicas (issue 15, item 6): what nginx and the Redis store add to a call, throughput of
one replica against three, and a replica killed under load — all in one run, on loopback, with
the servers tests/python/local_cluster.py starts (real redis-server, chasles-server, nginx).

    PYTHONPATH=build/python:clients/python /usr/bin/python3 bench/replicas.py [--calls 300] [--seconds 10]

Prints markdown tables (medians and p99 in ms; ratios against one replica on the memory store,
measured in the same run).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import threading
import time
from pathlib import Path
from typing import Callable, Dict, List

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests/python"))
from local_cluster import ROOT, LocalCluster  # noqa: E402

from chasles_client import Client  # noqa: E402
from chasles_client._stubs import pb  # noqa: E402

EXAMPLE = json.loads((ROOT / "examples/requests/panda_table.json").read_text())


def quantile(values: List[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * (len(ordered) - 1) + 0.5))]


def timed(call: Callable[[], object], n: int) -> List[float]:
    out = []
    for _ in range(n):
        started = time.perf_counter()
        call()
        out.append((time.perf_counter() - started) * 1e3)
    return out


def latency(address: str, calls: int, cell: str) -> Dict[str, List[float]]:
    """Per RPC: ListPlanners (transport), Plan by id (10 ms samples), CreateWorkcell (exists),
    CommitTrajectory + Release (a reservation written and removed)."""
    with Client(address, timeout=60.0) as client:
        robot_id = client.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf")
        planned = client.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"], robot_id=robot_id)
        stub = client.stub
        stub.CreateWorkcell(pb.CreateWorkcellRequest(name=cell), timeout=30)
        commit = pb.CommitTrajectoryRequest(workcell=cell, robot_name="bench", robot_id=robot_id,
                                            trajectory=planned.trajectory.to_message(), start_time=4.0e9)
        release = pb.ReleaseRequest(workcell=cell, robot_name="bench")

        def commit_release() -> None:
            stub.CommitTrajectory(commit, timeout=30)
            stub.Release(release, timeout=30)

        return {
            "ListPlanners": timed(lambda: client.planners(), calls),
            "Plan (by id)": timed(lambda: client.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"],
                                                      robot_id=robot_id, seed=1), calls // 3),
            "CreateWorkcell": timed(lambda: stub.CreateWorkcell(pb.CreateWorkcellRequest(name=cell), timeout=30), calls),
            "CommitTrajectory + Release": timed(commit_release, calls // 3),
        }


def throughput(address: str, seconds: float, threads: int) -> float:
    """Plans per second, `threads` clients planning panda_table (seeded 1..) for `seconds`."""
    done = [0]
    lock = threading.Lock()
    stop = time.monotonic() + seconds
    with Client(address, timeout=60.0) as client:
        client.wait_until_serving(timeout=20.0)

        def load(seed: int) -> None:
            while time.monotonic() < stop:
                result = client.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"], seed=seed)
                if result.success:
                    with lock:
                        done[0] += 1
                seed += threads

        workers = [threading.Thread(target=load, args=(s,)) for s in range(1, threads + 1)]
        started = time.monotonic()
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        return done[0] / (time.monotonic() - started)


def race(first: str, second: str, rounds: int) -> Dict[str, float]:
    """Two replicas commit conflicting trajectories (two robots of one model at one place and
    time) at the same moment, `rounds` times: rounds with exactly one winner, and the commit
    latency [ms] of both sides."""
    times: List[float] = []
    exactly_one = 0
    with Client(first, timeout=60.0) as a, Client(second, timeout=60.0) as b:
        robot_id = a.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf")
        planned = a.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"], robot_id=robot_id)
        trajectory = planned.trajectory.to_message()
        for k in range(rounds):
            cell = f"race{k}"
            a.stub.CreateWorkcell(pb.CreateWorkcellRequest(name=cell), timeout=30)
            outcomes: List[bool] = []
            barrier = threading.Barrier(2)

            def commit(client: Client, robot: str) -> None:
                request = pb.CommitTrajectoryRequest(workcell=cell, robot_name=robot, robot_id=robot_id,
                                                     trajectory=trajectory, start_time=4.0e9)
                barrier.wait()
                started = time.perf_counter()
                try:
                    client.stub.CommitTrajectory(request, timeout=30)
                    outcomes.append(True)
                except Exception:  # noqa: BLE001 - the loser's FAILED_PRECONDITION
                    outcomes.append(False)
                times.append((time.perf_counter() - started) * 1e3)

            threads = [threading.Thread(target=commit, args=(a, "left")),
                       threading.Thread(target=commit, args=(b, "right"))]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            exactly_one += 1 if sorted(outcomes) == [False, True] else 0
    return {"rounds": rounds, "exactly_one": exactly_one, "median": statistics.median(times),
            "p99": quantile(times, 0.99)}


def kill_under_load(cluster: LocalCluster, store: str, seconds: float, threads: int) -> Dict[str, float]:
    """Three more replicas, `threads` clients planning through the client-side balancer; one
    replica SIGKILLed a third of the way in: failed calls, and latency before and after."""
    replicas = [cluster.start_replica(store, threads=1) for _ in range(3)]
    victim = cluster.processes[-3]
    before: List[float] = []
    after: List[float] = []
    failures = [0]
    killed_at = [float("inf")]
    lock = threading.Lock()
    stop = time.monotonic() + seconds
    with Client(",".join(replicas), timeout=60.0) as client:
        client.wait_until_serving(timeout=20.0)

        def load(seed: int) -> None:
            while time.monotonic() < stop:
                started = time.monotonic()
                try:
                    ok = client.plan(EXAMPLE["start"]["positions"], EXAMPLE["goal"]["positions"], seed=seed).success
                except Exception:  # noqa: BLE001 - every failure counts
                    ok = False
                took = (time.monotonic() - started) * 1e3
                with lock:
                    (before if started < killed_at[0] else after).append(took)
                    failures[0] += 0 if ok else 1
                seed += threads

        workers = [threading.Thread(target=load, args=(s,)) for s in range(1, threads + 1)]
        for w in workers:
            w.start()
        time.sleep(seconds / 3)
        with lock:
            killed_at[0] = time.monotonic()
        victim.kill()
        for w in workers:
            w.join()
    return {"calls": len(before) + len(after), "failed": failures[0], "before_median": statistics.median(before),
            "before_p99": quantile(before, 0.99), "after_median": statistics.median(after),
            "after_p99": quantile(after, 0.99)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--server", default=str(ROOT / "build/bin/chasles-server"))
    args = parser.parse_args()

    cluster = LocalCluster(args.server)
    try:
        store = cluster.start_redis()
        alone = cluster.start_replica(threads=2)                 # memory store, direct
        shared = [cluster.start_replica(store, threads=2) for _ in range(3)]
        proxy = cluster.start_nginx(shared)
        setups = [("one replica, memory store (baseline)", alone),
                  ("one replica, Redis store", shared[0]),
                  ("three replicas behind nginx, Redis store", proxy)]
        results = {name: latency(address, args.calls, f"bench{k}") for k, (name, address) in enumerate(setups)}
        base = results[setups[0][0]]
        print(f"\n## Latency per call, {args.calls} calls (Plan and Commit+Release: a third of that)\n")
        print("| RPC | setup | median [ms] | p99 [ms] | median vs baseline |")
        print("|---|---|---|---|---|")
        for rpc in base:
            for name, _ in setups:
                values = results[name][rpc]
                ratio = statistics.median(values) / statistics.median(base[rpc])
                print(f"| {rpc} | {name} | {statistics.median(values):.3f} | {quantile(values, 0.99):.3f} | "
                      f"{ratio:.2f}× |")

        threads = 6
        one = throughput(shared[0], args.seconds, threads)
        three = throughput(",".join(shared), args.seconds, threads)
        print(f"\n## Throughput, {threads} client threads for {args.seconds:.0f} s (panda_table, RRT-Connect)\n")
        print("| setup | plans/s | vs one replica |")
        print("|---|---|---|")
        print(f"| one replica (2 worker threads) | {one:.1f} | 1.00× |")
        print(f"| three replicas (2 worker threads each), client-side round-robin | {three:.1f} | {three / one:.2f}× |")
        cores = os.cpu_count() or 1
        print(f"\nPer core ({cores} cores on this machine, every setup keeps them all busy): "
              f"{one / cores:.1f} and {three / cores:.1f} plans/s per core.")

        r = race(shared[0], shared[1], 100)
        print("\n## Two replicas committing conflicting trajectories at the same moment\n")
        print("| rounds | exactly one winner | commit median [ms] | commit p99 [ms] |")
        print("|---|---|---|---|")
        print(f"| {r['rounds']} | {r['exactly_one']} | {r['median']:.2f} | {r['p99']:.2f} |")

        k = kill_under_load(cluster, store, max(6.0, args.seconds), 4)
        print("\n## One of three replicas SIGKILLed under load (4 client threads, client-side balancing)\n")
        print("| calls | failed | median before [ms] | p99 before [ms] | median after [ms] | p99 after [ms] |")
        print("|---|---|---|---|---|---|")
        print(f"| {k['calls']} | {k['failed']} | {k['before_median']:.2f} | {k['before_p99']:.2f} | "
              f"{k['after_median']:.2f} | {k['after_p99']:.2f} |")
    finally:
        cluster.stop()


if __name__ == "__main__":
    main()
