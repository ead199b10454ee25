#!/usr/bin/python3
"""Plan on the server's default robot and scene (a Franka Panda at a table) and plot the result.

Run from the repository root with a server running (build/bin/chasles-server):

    PYTHONPATH=build/python:clients/python /usr/bin/python3 examples/python/plan_and_plot.py \
        --out panda_table.png

It uploads examples/robots/panda.urdf (the same model the server embeds as its default, so the
client learns its joint limits), plans the start and goal of examples/requests/panda_table.json
with RRT-Connect, prints the outcome and the trajectory's figures, and plots joint positions,
velocities and accelerations against time with the limits dashed (.png, .svg or .pdf).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from chasles_client import ChaslesError, Client
from chasles_client.plots import plot_trajectory

ROOT = Path(__file__).resolve().parents[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", default="127.0.0.1:50051", help="server address")
    parser.add_argument("--out", default="panda_table.png", help="plot file (.png, .svg or .pdf)")
    parser.add_argument("--planner", default="rrt_connect", help="planner id (see `python3 -m chasles_client planners`)")
    parser.add_argument("--post-processing", default="topp", choices=["topp", "collocation", "spline", "none"])
    args = parser.parse_args()

    example = json.loads((ROOT / "examples/requests/panda_table.json").read_text())
    start = example["start"]["positions"]
    goal = example["goal"]["positions"]

    with Client(args.server, timeout=60.0) as client:
        try:
            client.wait_until_serving(timeout=10.0)
            # The server's default robot is this URDF and SRDF named "panda": the upload gives the same
            # robot id, so the plan below (which names no robot) comes with its limits.
            client.upload_robot(ROOT / "examples/robots/panda.urdf", ROOT / "examples/robots/panda.srdf",
                                name="panda")
            result = client.plan(start, goal, planner=args.planner, time_budget=3.0, seed=7,
                                 post_processing=args.post_processing)
        except ChaslesError as error:
            print(f"request failed: {error}", file=sys.stderr)
            return 1

    print(f"{result.outcome}: {result.message}")
    if not result.success:
        return 1
    traj = result.trajectory
    print(f"{traj.dof} joints, {len(traj)} samples over {traj.duration:.3f} s; path of {len(result.path)} "
          f"waypoints, {result.statistics['path_length']:.3f} rad; planned in {result.timings['plan']:.3f} s")
    if result.velocity_limits is not None:
        peak = np.max(np.abs(traj.qd), axis=0) / result.velocity_limits
        print("peak |qd| / velocity limit per joint:", np.array2string(peak, precision=2))
    plot_trajectory(result, path=args.out, title=f"Panda at the table ({args.planner}, {result.optimizer['used']})")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
