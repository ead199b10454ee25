#!/usr/bin/env python3
"""Writes the example CoordinateRequests (chasles.v1.CoordinateRequest in protobuf JSON) in this
folder, and the two box scenes they use in ../scenes.

  coordinate_crossing_arms.json  two Pandas facing each other across one table; each sweeps its hand
                                 from its own side of the table to a place over the middle, crossing
                                 the other's sweep (scene two_arm_table.json)
  coordinate_swap_bases.json     four mobile bases swap the diagonally opposite corners of a 3 m
                                 square in a room with pillars (the OctoMap pillar_room_octomap.json)
  coordinate_corridor.json       two mobile bases head-on in a corridor with one passing bay halfway;
                                 they swap ends, so one has to duck into the bay (corridor_bay.json)
  coordinate_goals_overlap.json  infeasible: two bases both sent to park in that one bay (their bodies
                                 would intersect at the goals); the answer is GOALS_IN_CONFLICT

Every robot is carried inline (TeamRobot.robot; the Panda's URDF/SRDF text from ../robots), placed
by its base pose in the scene (world) frame. tests/multi/examples_test.cc checks that every start
and goal is collision-free against the scene and the robot itself, that the starts (and, but for the
overlapping goals, the goals) do not collide pairwise, and that the naive plan — every robot on the
straight joint-space line from start to goal, all at once at the same normalised progress —
collides robot against robot (so the examples need coordination); for the overlapping goals, that
the goals collide.

The pillar room's primitives come from ../tools/make_maps.py and its OctoMap from
chasles-scene-to-octomap (see ../scenes/README.md); this script only reads
../scenes/pillar_room_octomap.json.

Usage: python3 make_coordination.py   (python3 standard library only; rewrites the files above)
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.path.dirname(HERE)

TIME_BUDGET = 30.0
SEED = "11"  # uint64 is a string in protobuf JSON
# A heading of π, kept inside the planar bases' heading limits [-π, π] after rounding.
PI = 3.14159


def read(path):
    with open(os.path.join(EXAMPLES, path), encoding="utf-8") as f:
        return f.read()


def r(v):
    return round(v, 6)


def pose(x, y, z=0.0, yaw=0.0):
    """A pose in protobuf JSON: position and a rotation of `yaw` about z."""
    return {"position": {"x": r(x), "y": r(y), "z": r(z)},
            "orientation": {"x": 0, "y": 0, "z": r(math.sin(yaw / 2)), "w": r(math.cos(yaw / 2))}}


def box(name, x0, x1, y0, y1, z0, z1):
    return {"name": name, "size": {"x": r(x1 - x0), "y": r(y1 - y0), "z": r(z1 - z0)},
            "pose": pose((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2)}


# ---------------------------------------------------------------------------------------------
# a. Two Pandas across one table.
#
# "left" stands at the origin facing +x, "right" at (1.1, 0, 0) turned by π about z (facing −x):
# 1.1 m between the bases, the table between them (top x 0.30…0.80, y ±0.50, surface z = 0.20) with
# a low tray in its middle. Both use the same joint values in their own base frames, so the layout is
# point-symmetric about the table centre (0.55, 0). Hand pointing down, TCP (panda_tcp) positions in
# the robot's own base frame (world for "left"; world = (1.1 − x, −y) for "right"):
#   start: TCP (0.30, −0.35, 0.35) — the robot's own side of the table, to its right
#   goal:  TCP (0.55, +0.25, 0.35) — over the middle of the table, to its left
# So "left" sweeps from world (0.30, −0.35) to (0.55, 0.25) while "right" sweeps from (0.80, 0.35)
# to (0.55, −0.25): at the same progress their hands meet over the tray (the straight joint-space
# lines collide from about 50 % to 80 % of the way, up to 9 cm deep). The goals keep 0.29 m
# between the robots, each goal 0.17 m from the other robot's start, and each robot alone moves
# on its straight line clear of the table and tray by more than 0.1 m. The right robot moving
# straight to its goal after the left one has arrived still touches it: the second robot to move
# has to go around the first, not just wait. Configurations from a damped least-squares IK, rounded
# to 1e-3 rad (TCP within 1 mm of the targets).
PANDA_START = [-0.039, -0.387, -0.752, -2.306, -0.288, 2.0, 0.155]
PANDA_GOAL = [0.063, 0.166, 0.389, -1.813, -0.068, 1.965, 1.258]
ARM_BASE_DISTANCE = 1.1


def two_arm_table_scene():
    boxes = [box("table_top", 0.30, 0.80, -0.50, 0.50, 0.16, 0.20)]
    for k, (x, y) in enumerate([(0.32, 0.48), (0.32, -0.48), (0.78, 0.48), (0.78, -0.48)]):
        boxes.append(box(f"table_leg_{k}", x - 0.02, x + 0.02, y - 0.02, y + 0.02, 0.0, 0.16))
    boxes.append(box("tray", 0.45, 0.65, -0.10, 0.10, 0.20, 0.24))
    return {"boxes": boxes}


def panda_message():
    return {"name": "panda", "urdf": {"urdf": read("robots/panda.urdf"), "srdf": read("robots/panda.srdf")}}


def crossing_arms_request(scene):
    robots = []
    for name, base, priority in [("left", pose(0, 0), 2), ("right", pose(ARM_BASE_DISTANCE, 0, yaw=math.pi), 1)]:
        robots.append({"name": name, "robot": panda_message(), "basePose": base,
                       "start": {"positions": PANDA_START}, "goal": {"positions": PANDA_GOAL},
                       "priority": priority})
    return {"requestId": "coordinate_crossing_arms", "scene": scene, "robots": robots, "method": "AUTO",
            "timeBudget": TIME_BUDGET, "seed": SEED}


# ---------------------------------------------------------------------------------------------
# Mobile bases: examples/robots/mobile_base.json (PLANAR; x, y [m], theta [rad]; two spheres
# r 0.2 m at x = ±0.15, a 0.7 m × 0.4 m footprint), with the workspace narrowed to each floor.

def mobile_base_message(workspace_min, workspace_max):
    mobile = json.loads(read("robots/mobile_base.json"))
    mobile["workspace_min"] = dict(zip("xyz", workspace_min))
    mobile["workspace_max"] = dict(zip("xyz", workspace_max))
    return {"mobile": mobile}


def base_robot(name, robot, start, goal, priority):
    return {"name": name, "robot": robot, "start": {"positions": start}, "goal": {"positions": goal},
            "priority": priority}


# b. Four bases swap the diagonally opposite corners of the square (2.5…5.5)² in the 8 m × 8 m
# pillar room (OctoMap at 0.05 m; pillars beside the middle of each side of the square, outside
# it). Each keeps its heading along its diagonal, so the naive plan puts all four at the centre
# (4, 4) at half-way.
SQUARE_LOW, SQUARE_HIGH = 2.5, 5.5
SWAP = [  # name, start corner, heading, priority
    ("base_sw", (SQUARE_LOW, SQUARE_LOW), math.pi / 4, 4),
    ("base_se", (SQUARE_HIGH, SQUARE_LOW), 3 * math.pi / 4, 3),
    ("base_ne", (SQUARE_HIGH, SQUARE_HIGH), -3 * math.pi / 4, 2),
    ("base_nw", (SQUARE_LOW, SQUARE_HIGH), -math.pi / 4, 1),
]


def swap_bases_request():
    robot = mobile_base_message((0.0, 0.0, 0.0), (8.0, 8.0, 0.0))
    robots = []
    for name, (x, y), heading, priority in SWAP:
        opposite = (SQUARE_LOW + SQUARE_HIGH - x, SQUARE_LOW + SQUARE_HIGH - y)
        robots.append(base_robot(name, robot, [x, y, r(heading)], [*opposite, r(heading)], priority))
    return {"requestId": "coordinate_swap_bases", "scene": json.loads(read("scenes/pillar_room_octomap.json")),
            "robots": robots, "method": "AUTO", "timeBudget": TIME_BUDGET, "seed": SEED}


# c./d. A straight corridor along x, 8 m long, 0.75 m clear (y 0.625…1.375, centre line y = 1.0):
# two bases (0.4 m wide) cannot pass each other in it (they would need 0.8 m). Halfway, on the
# north side, a passing bay x 3.4…4.6 (1.2 m long), y up to 2.05 (0.675 m deep): a base parked in
# it at y = 1.75 keeps 0.15 m from the bay's ends and 0.1 m from its back, and 0.35 m from a base
# passing on the centre line. Walls 0.1 m thick and 1.0 m tall, all boxes.
CORRIDOR_Y, CORRIDOR_HALF_WIDTH = 1.0, 0.375
BAY_X0, BAY_X1, BAY_Y1 = 3.4, 4.6, 2.05
CORRIDOR_LENGTH, WALL, WALL_HEIGHT = 8.0, 0.1, 1.0
CORRIDOR_WORKSPACE = ((0.0, 0.0, 0.0), (CORRIDOR_LENGTH, 2.5, 0.0))
WEST_END, EAST_END = [0.8, CORRIDOR_Y, 0.0], [7.2, CORRIDOR_Y, PI]


def corridor_bay_scene():
    south = CORRIDOR_Y - CORRIDOR_HALF_WIDTH
    north = CORRIDOR_Y + CORRIDOR_HALF_WIDTH
    boxes = [
        box("wall_south", 0.0, CORRIDOR_LENGTH, south - WALL, south, 0.0, WALL_HEIGHT),
        box("wall_north_west", 0.0, BAY_X0, north, north + WALL, 0.0, WALL_HEIGHT),
        box("wall_north_east", BAY_X1, CORRIDOR_LENGTH, north, north + WALL, 0.0, WALL_HEIGHT),
        box("bay_west", BAY_X0 - WALL, BAY_X0, north, BAY_Y1 + WALL, 0.0, WALL_HEIGHT),
        box("bay_east", BAY_X1, BAY_X1 + WALL, north, BAY_Y1 + WALL, 0.0, WALL_HEIGHT),
        box("bay_back", BAY_X0, BAY_X1, BAY_Y1, BAY_Y1 + WALL, 0.0, WALL_HEIGHT),
        box("end_west", 0.0, WALL, south, north, 0.0, WALL_HEIGHT),
        box("end_east", CORRIDOR_LENGTH - WALL, CORRIDOR_LENGTH, south, north, 0.0, WALL_HEIGHT),
    ]
    return {"boxes": boxes}


def corridor_request(scene):
    # "west" drives east (heading 0) and "east" drives west (heading π), head-on; they swap ends.
    robot = mobile_base_message(*CORRIDOR_WORKSPACE)
    robots = [base_robot("west", robot, WEST_END, [EAST_END[0], CORRIDOR_Y, 0.0], 2),
              base_robot("east", robot, EAST_END, [WEST_END[0], CORRIDOR_Y, PI], 1)]
    return {"requestId": "coordinate_corridor", "scene": scene, "robots": robots, "method": "AUTO",
            "timeBudget": TIME_BUDGET, "seed": SEED}


def goals_overlap_request(scene):
    # Both bases are sent to park in the one bay, their centres 0.2 m apart: each goal alone is
    # free (the bay holds one base), together the bodies intersect.
    robot = mobile_base_message(*CORRIDOR_WORKSPACE)
    bay_x, bay_y = (BAY_X0 + BAY_X1) / 2, 1.75
    robots = [base_robot("west", robot, WEST_END, [r(bay_x - 0.1), bay_y, 0.0], 2),
              base_robot("east", robot, EAST_END, [r(bay_x + 0.1), bay_y, PI], 1)]
    return {"requestId": "coordinate_goals_overlap", "scene": scene, "robots": robots, "method": "AUTO",
            "timeBudget": TIME_BUDGET, "seed": SEED}


def write(path, message):
    full = os.path.join(EXAMPLES, path)
    with open(full, "w", encoding="utf-8") as f:
        json.dump(message, f, indent=1)
        f.write("\n")
    print(f"wrote {path}")


def main():
    table = two_arm_table_scene()
    corridor = corridor_bay_scene()
    write("scenes/two_arm_table.json", table)
    write("scenes/corridor_bay.json", corridor)
    write("requests/coordinate_crossing_arms.json", crossing_arms_request(table))
    write("requests/coordinate_swap_bases.json", swap_bases_request())
    write("requests/coordinate_corridor.json", corridor_request(corridor))
    write("requests/coordinate_goals_overlap.json", goals_overlap_request(corridor))


if __name__ == "__main__":
    main()
