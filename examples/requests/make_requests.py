#!/usr/bin/env python3
"""Writes the example PlanRequests (chasles.v1.PlanRequest in protobuf JSON) in this folder.

Each request is assembled from the robot files in ../robots, the scene files in ../scenes and the
table PROBLEMS below (start and goal configurations, checked collision-free and solvable against
the server: tests/server/end_to_end_test.cc plans every request). The Panda and the table scene are
the server's defaults, so requests that use them leave the robot/scene out; every other robot and
scene is carried inline.

Usage: python3 make_requests.py   (python3 standard library only; rewrites *.json here)
"""
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.path.dirname(HERE)

# The server's embedded defaults (server/CMakeLists.txt).
DEFAULT_ROBOT = "panda"
DEFAULT_SCENE = "table"

PANDA_READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
UR5_UP = [0.0, -1.571, 0.0, -1.571, 0.0, 0.0]

# A scene of its own for the planar arm: posts that stand in its plane of motion (z = 0.05…0.15 m).
PLANAR_POSTS = {
    "cylinders": [
        {"name": "post_a", "radius": 0.08, "length": 0.4,
         "pose": {"position": {"x": 1.2, "y": 0.6, "z": 0.2}}},
        {"name": "post_b", "radius": 0.08, "length": 0.4,
         "pose": {"position": {"x": -0.9, "y": 0.9, "z": 0.2}}},
    ],
    "boxes": [
        {"name": "wall", "size": {"x": 0.1, "y": 0.6, "z": 0.4},
         "pose": {"position": {"x": 0.0, "y": -1.3, "z": 0.2}}},
    ],
}

# name: (robot, scene, start, goal, extra fields)
PROBLEMS = {
    "panda_table": ("panda", "table", PANDA_READY, [-1.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785], {}),
    "panda_shelf": ("panda", "shelf", PANDA_READY, [2.5, -0.5, 0.0, -2.0, 0.0, 1.6, 0.785], {}),
    "panda_cage": ("panda", "cage", PANDA_READY, [-2.0, -0.3, 0.0, -2.4, 0.0, 2.0, 0.785], {}),
    "panda_shelf_octomap": ("panda", "shelf_octomap", PANDA_READY, [2.5, -0.5, 0.0, -2.0, 0.0, 1.6, 0.785], {}),
    "ur5_table": ("ur5", "table", UR5_UP, [1.5, -1.2, 1.0, -1.4, -1.571, 0.0], {}),
    "ur5_shelf": ("ur5", "shelf", UR5_UP, [-2.5, -1.2, 1.2, -1.5, -1.571, 0.5], {}),
    "ur5_cage": ("ur5", "cage", UR5_UP, [2.0, -1.0, 1.0, -1.5, 1.571, 0.0], {}),
    "planar_2r_table": ("planar_2r", "table", [0.3, -1.0], [-0.3, 1.0], {}),
    "planar_2r_shelf": ("planar_2r", "shelf", [1.2, 0.5], [2.8, -1.0], {}),
    "planar_2r_cage": ("planar_2r", "cage", [-0.5, 0.3], [0.6, -2.0], {}),
    "planar_2r_posts": ("planar_2r", PLANAR_POSTS, [0.0, 0.0], [2.8, 0.5], {}),
}


def read(path):
    with open(os.path.join(EXAMPLES, path), encoding="utf-8") as f:
        return f.read()


def robot_message(name):
    urdf = {"urdf": read(f"robots/{name}.urdf")}
    srdf_path = os.path.join(EXAMPLES, "robots", f"{name}.srdf")
    if os.path.exists(srdf_path):
        urdf["srdf"] = read(f"robots/{name}.srdf")
    return {"name": name, "urdf": urdf}


def make_request(name, robot, scene, start, goal, extra):
    request = {"requestId": name}
    if robot != DEFAULT_ROBOT:
        request["robot"] = robot_message(robot)
    if isinstance(scene, dict):
        request["scene"] = scene
    elif scene != DEFAULT_SCENE:
        request["scene"] = json.loads(read(f"scenes/{scene}.json"))
    request["start"] = {"positions": start}
    request["goal"] = {"positions": goal}
    request["planner"] = {"plannerId": "rrt_connect"}
    request["timeBudget"] = 3.0
    request["seed"] = "7"  # uint64 is a string in protobuf JSON
    request.update(extra)
    return request


def main():
    for name, (robot, scene, start, goal, extra) in sorted(PROBLEMS.items()):
        path = os.path.join(HERE, f"{name}.json")
        with open(path, "w", encoding="utf-8") as f:
            json.dump(make_request(name, robot, scene, start, goal, extra), f, indent=1)
            f.write("\n")
        print(f"wrote {os.path.relpath(path, EXAMPLES)}")


if __name__ == "__main__":
    main()
