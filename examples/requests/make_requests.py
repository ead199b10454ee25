#!/usr/bin/env python3
"""Writes the example PlanRequests (chasles.v1.PlanRequest in protobuf JSON) in this folder.

Each request is assembled from the robot files in ../robots, the scene files in ../scenes and the
table PROBLEMS below (start and goal configurations, checked collision-free and solvable against
the server: tests/server/end_to_end_test.cc plans every request). The Panda and the table scene are
the server's defaults, so requests that use them leave the robot/scene out; every other robot and
scene is carried inline.

Pose-goal requests (issue 3) take their target from forward kinematics of a known collision-free
configuration (POSE_PROBLEMS below: the configuration is the "expected" solution; IK may find another
one), computed here from the URDF / DH / PoE description itself, so every target is reachable.
The ik_*.json files are chasles.v1.InverseKinematicsRequests built the same way.

Usage: python3 make_requests.py   (python3 standard library only; rewrites *.json here)
"""
import json
import math
import os
import xml.etree.ElementTree as ET

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


# ---------------------------------------------------------------------------------------------
# Forward kinematics in plain Python (4×4 homogeneous matrices as nested lists).

def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def identity():
    return [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def translation(x, y, z):
    t = identity()
    t[0][3], t[1][3], t[2][3] = x, y, z
    return t


def rotation_axis_angle(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    x, y, z = (a / n for a in axis)
    c, s, v = math.cos(angle), math.sin(angle), 1.0 - math.cos(angle)
    return [[c + x * x * v, x * y * v - z * s, x * z * v + y * s, 0.0],
            [y * x * v + z * s, c + y * y * v, y * z * v - x * s, 0.0],
            [z * x * v - y * s, z * y * v + x * s, c + z * z * v, 0.0],
            [0.0, 0.0, 0.0, 1.0]]


def rpy(r, p, y):
    return matmul(rotation_axis_angle((0, 0, 1), y),
                  matmul(rotation_axis_angle((0, 1, 0), p), rotation_axis_angle((1, 0, 0), r)))


def quaternion_from_matrix(m):
    """(x, y, z, w) with w >= 0."""
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        w, x, y, z = (m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        w, x, y, z = (m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        w, x, y, z = (m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    return x, y, z, w


def pose_message(m):
    x, y, z, w = quaternion_from_matrix(m)
    r = lambda v: round(v, 12)
    return {"position": {"x": r(m[0][3]), "y": r(m[1][3]), "z": r(m[2][3])},
            "orientation": {"x": r(x), "y": r(y), "z": r(z), "w": r(w)}}


def matrix_from_pose(pose):
    pos = pose.get("position", {})
    o = pose.get("orientation", {})
    x, y, z, w = (o.get(k, 0.0) for k in ("x", "y", "z", "w"))
    if x == y == z == w == 0:
        m = identity()
    else:
        n = math.sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x / n, y / n, z / n, w / n
        m = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 0.0],
             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), 0.0],
             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), 0.0],
             [0.0, 0.0, 0.0, 1.0]]
    m[0][3], m[1][3], m[2][3] = (pos.get(k, 0.0) for k in ("x", "y", "z"))
    return m


def urdf_fk(name, q, link):
    """Pose of `link` (base frame) for a serial URDF chain; q in the URDF's active-joint order."""
    root = ET.fromstring(read(f"robots/{name}.urdf"))
    joints = {j.find("child").get("link"): j for j in root.findall("joint")}
    chain = []
    while link in joints:
        chain.append(joints[link])
        link = joints[link].find("parent").get("link")
    chain.reverse()
    active = [j for j in root.findall("joint") if j.get("type") != "fixed"]
    t = identity()
    for j in chain:
        o = j.find("origin")
        xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        r = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        t = matmul(t, matmul(translation(*xyz), rpy(*r)))
        if j.get("type") == "fixed":
            continue
        axis = [float(v) for v in j.find("axis").get("xyz").split()]
        qi = q[active.index(j)]
        if j.get("type") == "prismatic":
            t = matmul(t, translation(*(a * qi for a in axis)))
        else:
            t = matmul(t, rotation_axis_angle(axis, qi))
    return t


def rot_x(a):
    return rotation_axis_angle((1, 0, 0), a)


def rot_z(a):
    return rotation_axis_angle((0, 0, 1), a)


def dh_fk(dh, q):
    """Tool pose of a chasles.v1.DhRobot (dict in protobuf JSON) at q."""
    modified = dh.get("convention", "STANDARD") == "MODIFIED"
    t = matrix_from_pose(dh["base"]) if "base" in dh else identity()
    for joint, qi in zip(dh["joints"], q):
        a, alpha, d = joint.get("a", 0.0), joint.get("alpha", 0.0), joint.get("d", 0.0)
        theta = joint.get("thetaOffset", joint.get("theta_offset", 0.0))
        if joint.get("type", "REVOLUTE") == "PRISMATIC":
            d += qi
        else:
            theta += qi
        if modified:
            step = matmul(matmul(rot_x(alpha), translation(a, 0, 0)), matmul(rot_z(theta), translation(0, 0, d)))
        else:
            step = matmul(matmul(rot_z(theta), translation(0, 0, d)), matmul(translation(a, 0, 0), rot_x(alpha)))
        t = matmul(t, step)
    if "tool" in dh:
        t = matmul(t, matrix_from_pose(dh["tool"]))
    return t


def exp_screw(w, v, theta):
    if max(abs(c) for c in w) < 1e-12:
        return translation(*(c * theta for c in v))
    r = rotation_axis_angle(w, theta)
    # p = (Iθ + (1 − cos θ)[ω] + (θ − sin θ)[ω]²) v
    k = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
    k2 = [[sum(k[i][m] * k[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    g = [[(theta if i == j else 0.0) + (1 - math.cos(theta)) * k[i][j] + (theta - math.sin(theta)) * k2[i][j]
          for j in range(3)] for i in range(3)]
    for i in range(3):
        r[i][3] = sum(g[i][j] * v[j] for j in range(3))
    return r


def poe_fk(poe, q):
    """Tool pose (M) of a chasles.v1.PoeRobot (dict in protobuf JSON) at q."""
    home = matrix_from_pose(poe.get("home", {}))
    vec = lambda d: [d.get(k, 0.0) for k in ("x", "y", "z")]
    exps = [exp_screw(vec(j["screw"].get("angular", {})), vec(j["screw"].get("linear", {})), qi)
            for j, qi in zip(poe["joints"], q)]
    t = identity()
    for e in exps:
        t = matmul(t, e)
    if poe.get("bodyFrame", poe.get("body_frame", False)):
        return matmul(home, t)
    return matmul(t, home)


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


# Pose goals (issue 3). name: (robot, scene, start, link, expected configuration, extra fields).
# `robot` is a URDF name, or ("dh" | "poe", file in ../robots). The target is FK(expected) of `link`
# ("" = the robot's "tool" link); the expected configuration is collision-free in the scene (it is
# the goal of the joint-goal request of the same robot and scene above, or checked by the tests).
PANDA_PLACE = [-1.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785]
UR5_PLACE = [1.5, -1.2, 1.0, -1.4, -1.571, 0.0]
PUMA_READY = [0.0, 0.5, -0.8, 0.0, 0.3, 0.0]
PUMA_PLACE = [1.2, 0.2, -0.4, 0.5, 0.8, 0.3]
POSE_PROBLEMS = {
    "panda_pose_table": ("panda", "table", PANDA_READY, "panda_tcp", PANDA_PLACE, {}),
    "ur5_pose_table": ("ur5", "table", UR5_UP, "tool0", UR5_PLACE, {}),
    "ur5_dh_pose": (("dh", "ur5_dh.json"), "table", UR5_UP, "", UR5_PLACE, {}),
    "ur5_poe_pose": (("poe", "ur5_poe.json"), "table", UR5_UP, "", UR5_PLACE, {}),
    "puma560_dh_pose": (("dh", "puma560_dh.json"), "table", PUMA_READY, "", PUMA_PLACE, {}),
}

# InverseKinematicsRequests. name: (robot, link, expected configuration, extra fields).
IK_PROBLEMS = {
    "ik_panda": ("panda", "panda_tcp", PANDA_PLACE,
                 {"maxSolutions": 4, "collisionFree": True, "timeBudget": 0.5}),
    "ik_ur5": ("ur5", "tool0", UR5_PLACE, {"maxSolutions": 8, "collisionFree": True, "timeBudget": 0.5}),
}


def described_robot(robot):
    """(RobotModel message, FK function of (q, link)) of a URDF name or a ("dh"|"poe", file)."""
    if isinstance(robot, tuple):
        kind, path = robot
        description = json.loads(read(f"robots/{path}"))
        name = description.get("name") or os.path.splitext(path)[0]
        fk = dh_fk if kind == "dh" else poe_fk
        return {"name": name, kind: description}, lambda q, link: fk(description, q)
    return robot_message(robot), lambda q, link: urdf_fk(robot, q, link)


def make_pose_request(name, robot, scene, start, link, expected, extra):
    request = {"requestId": name}
    if robot != DEFAULT_ROBOT:
        request["robot"], fk = described_robot(robot)
    else:
        fk = lambda q, l: urdf_fk(robot, q, l)
    if isinstance(scene, dict):
        request["scene"] = scene
    elif scene != DEFAULT_SCENE:
        request["scene"] = json.loads(read(f"scenes/{scene}.json"))
    request["start"] = {"positions": start}
    goal = {"pose": pose_message(fk(expected, link))}
    if link:
        goal = {"link": link, **goal}
    request["poseGoal"] = goal
    request["planner"] = {"plannerId": "rrt_connect"}
    request["timeBudget"] = 3.0
    request["seed"] = "7"
    request.update(extra)
    return request


def make_ik_request(name, robot, link, expected, extra):
    request = {}
    if robot != DEFAULT_ROBOT:
        request["robot"], fk = described_robot(robot)
    else:
        fk = lambda q, l: urdf_fk(robot, q, l)
    request["link"] = link
    request["pose"] = pose_message(fk(expected, link))
    request["seed"] = "7"
    request.update(extra)
    return request


# CartesianPathRequests: the link drawn along straight lines through poses offset from its pose at
# the start (orientation kept). name: (robot, link, start, offsets [m] of the waypoints, extra).
CARTESIAN_PROBLEMS = {
    "cartesian_panda_table": ("panda", "panda_tcp", PANDA_READY,
                              [(0.0, 0.2, 0.0), (0.0, 0.2, -0.15), (0.0, -0.2, -0.15), (0.0, -0.2, 0.0), (0.0, 0.0, 0.0)],
                              {"options": {"samplePeriod": 0.01}}),
}


# A PlanRequest carrying an object: a 40 cm rod held in the gripper, pointing down, carried across
# a block on the floor that the bare arm would sweep straight over (the rod would go through it).
def make_carry_request():
    start = list(PANDA_READY)
    goal = list(PANDA_READY)
    start[0], goal[0] = 0.6, -0.6
    block = {"name": "block", "size": {"x": 0.1, "y": 0.1, "z": 0.1}, "pose": {"position": {"x": 0.307, "z": 0.05}}}
    rod = {"name": "rod", "link": "panda_tcp", "touchLinks": ["panda_hand"],
           "boxes": [{"size": {"x": 0.04, "y": 0.04, "z": 0.4}, "pose": {"position": {"z": 0.2}}}]}
    return {"requestId": "panda_carry_rod", "scene": {"boxes": [block]}, "start": {"positions": start},
            "goal": {"positions": goal}, "planner": {"plannerId": "rrt_connect"}, "timeBudget": 5.0, "seed": "7",
            "attachedObjects": [rod]}


def make_cartesian_request(name, robot, link, start, offsets, extra):
    at = urdf_fk(robot, start, link)
    waypoints = []
    for offset in offsets:
        m = [row[:] for row in at]
        for axis in range(3):
            m[axis][3] = at[axis][3] + offset[axis]
        waypoints.append(pose_message(m))
    request = {"requestId": name, "start": {"positions": start}, "link": link, "waypoints": waypoints}
    request.update(extra)
    return request


# Mobile robots (issue 4) on the OctoMap maps, one request per planner family.
# name: (robot file in ../robots, workspace (min, max) override or None, scene, start, goal, planner).
MAZE = ((0.0, 0.0, 0.0), (8.0, 8.0, 0.0))
MAZE_START, MAZE_GOAL = [0.7, 0.7, 0.0], [7.3, 7.3, 0.0]
OFFICE_START, OFFICE_GOAL = [1.0, 4.0, 0.0], [10.5, 1.5, 0.0]
DRONE_START, DRONE_GOAL = [1.0, 5.0, 1.5, 0.0, 0.0, 0.0], [9.0, 5.0, 2.5, 0.0, 0.0, 0.0]
MOBILE_PROBLEMS = {
    "maze_astar": ("mobile_base", MAZE, "maze_octomap", MAZE_START, MAZE_GOAL, "astar"),
    "maze_wavefront": ("mobile_base", MAZE, "maze_octomap", MAZE_START, MAZE_GOAL, "wavefront"),
    "maze_rrt_connect": ("mobile_base", MAZE, "maze_octomap", MAZE_START, MAZE_GOAL, "rrt_connect"),
    "office_astar": ("mobile_base", None, "office_octomap", OFFICE_START, OFFICE_GOAL, "astar"),
    "office_wavefront": ("mobile_base", None, "office_octomap", OFFICE_START, OFFICE_GOAL, "wavefront"),
    "office_rrt_connect": ("mobile_base", None, "office_octomap", OFFICE_START, OFFICE_GOAL, "rrt_connect"),
    "office_car": ("car", None, "office_octomap", [1.0, 4.0, 0.0], [10.5, 4.0, 3.14159], "rrt_connect"),
    "drone_astar": ("drone", None, "drone_course_octomap", DRONE_START, DRONE_GOAL, "astar"),
    "drone_potential_field": ("drone", None, "drone_course_octomap", DRONE_START, DRONE_GOAL, "potential_field"),
    "drone_wavefront": ("drone", None, "drone_course_octomap", DRONE_START, DRONE_GOAL, "wavefront"),
    "drone_rrt_connect": ("drone", None, "drone_course_octomap", DRONE_START, DRONE_GOAL, "rrt_connect"),
}


def make_mobile_request(name, robot, workspace, scene, start, goal, planner):
    mobile = json.loads(read(f"robots/{robot}.json"))
    if workspace is not None:
        lo, hi = workspace
        mobile["workspace_min"] = dict(zip("xyz", lo))
        mobile["workspace_max"] = dict(zip("xyz", hi))
    return {
        "requestId": name,
        "robot": {"mobile": mobile},
        "scene": json.loads(read(f"scenes/{scene}.json")),
        "start": {"positions": start},
        "goal": {"positions": goal},
        "planner": {"plannerId": planner},
        "timeBudget": 5.0,
        "seed": "7",
    }


def write(name, message):
    path = os.path.join(HERE, f"{name}.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(message, f, indent=1)
        f.write("\n")
    print(f"wrote {os.path.relpath(path, EXAMPLES)}")


def main():
    for name, (robot, scene, start, goal, extra) in sorted(PROBLEMS.items()):
        write(name, make_request(name, robot, scene, start, goal, extra))
    for name, problem in sorted(POSE_PROBLEMS.items()):
        robot = problem[0]
        if isinstance(robot, tuple) and not os.path.exists(os.path.join(EXAMPLES, "robots", robot[1])):
            print(f"skipped {name}: robots/{robot[1]} does not exist")
            continue
        write(name, make_pose_request(name, *problem))
    for name, problem in sorted(IK_PROBLEMS.items()):
        write(name, make_ik_request(name, *problem))
    for name, problem in sorted(MOBILE_PROBLEMS.items()):
        write(name, make_mobile_request(name, *problem))
    for name, problem in sorted(CARTESIAN_PROBLEMS.items()):
        write(name, make_cartesian_request(name, *problem))
    write("panda_carry_rod", make_carry_request())


if __name__ == "__main__":
    main()
