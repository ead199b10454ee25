#!/usr/bin/env python3
"""Writes coordinate_fleet.json: a fleet of 60 disc bases (0.4 m radius, 1 m/s) on a 32 x 32 m
floor with 20 % of its 1 m cells blocked by boxes, in the style of the MAPF benchmark map
random-32-32-20 (cells blocked at random, then every free cell outside the largest connected
free region blocked too). Robots start and end at cell centres, 1 m apart on the fleet lattice
(fleet_resolution 1 m), so Coordinate's AUTO picks FLEET; the answer comes as knots
(knots_only).

Usage: python3 make_fleet.py   (python3 standard library only; deterministic)
"""
import json
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))
SIZE = 32
ROBOTS = 60


def main():
    rng = random.Random(20)
    cells = [(x, y) for y in range(SIZE) for x in range(SIZE)]
    blocked = set(rng.sample(cells, round(0.2 * SIZE * SIZE)))
    # The largest 4-connected free region stays free.
    seen, best = set(), set()
    for cell in cells:
        if cell in blocked or cell in seen:
            continue
        region, stack = set(), [cell]
        while stack:
            c = stack.pop()
            if c in region or c in blocked or not (0 <= c[0] < SIZE and 0 <= c[1] < SIZE):
                continue
            region.add(c)
            stack += [(c[0] + 1, c[1]), (c[0] - 1, c[1]), (c[0], c[1] + 1), (c[0], c[1] - 1)]
        seen |= region
        if len(region) > len(best):
            best = region
    free = sorted(best)
    boxes = [{"name": "cell_%d_%d" % (x, y), "size": {"x": 1, "y": 1, "z": 1},
              "pose": {"position": {"x": x + 0.5, "y": y + 0.5, "z": 0.5}}}
             for (x, y) in cells if (x, y) not in best]
    starts = rng.sample(free, ROBOTS)
    goals = rng.sample(free, ROBOTS)
    body = {"spheres": [{"name": "disc", "radius": 0.4, "pose": {"position": {"x": 0, "y": 0, "z": 0.4}}}]}
    robot = {"mobile": {"name": "disc_base", "kind": "PLANAR", "workspace_min": {"x": 0, "y": 0, "z": 0},
                        "workspace_max": {"x": SIZE, "y": SIZE, "z": 0}, "linear_velocity": 1.0,
                        "angular_velocity": 1.0, "body": body}}
    request = {
        "scene": {"boxes": boxes},
        "robots": [{"name": "r%02d" % k, "robot": robot,
                    "start": {"positions": [s[0] + 0.5, s[1] + 0.5, 0.0]},
                    "goal": {"positions": [g[0] + 0.5, g[1] + 0.5, 0.0]}}
                   for k, (s, g) in enumerate(zip(starts, goals))],
        "method": "AUTO",
        "timeBudget": 10.0,
        "seed": "1",
        "fleetResolution": 1.0,
        "knotsOnly": True,
    }
    with open(os.path.join(HERE, "coordinate_fleet.json"), "w", encoding="utf-8") as f:
        json.dump(request, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
