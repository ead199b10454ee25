#!/usr/bin/env python3
"""Builds a self-contained viewer page for checking the browser side by hand or in headless Chromium.

    python3 make_sample.py OUT.html                 # template + three.js + viewer + sample_view.json
    python3 make_sample.py OUT.html --view V.json   # another view file
    python3 make_sample.py OUT.html --big [--voxels N]
                                                    # load test: 12-link robot, 10 s at 100 frames/s,
                                                    # 2000 plot points, N voxels (generated, not stored)
    python3 make_sample.py --regenerate             # rewrite sample_view.json (3-link arm on a table)

The page is assembled the way `chasles view` does it: each placeholder line of template.html
(/*@CSS@*/, /*@THREE@*/, /*@ORBIT@*/, /*@DATA@*/, /*@VIEWER@*/) is replaced by a file's contents.
Python 3 standard library only.
"""

import argparse
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
THREE_JS = "/usr/share/javascript/three/build/three.min.js"
ORBIT_JS = "/usr/share/javascript/three/examples/js/controls/OrbitControls.js"
SAMPLE = os.path.join(HERE, "sample_view.json")


# --------------------------------------------------------------------------------------------
# Page assembly
# --------------------------------------------------------------------------------------------

def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def data_script(view):
    # "</" must not appear inside a <script> element: "<\/" is the same string in JavaScript.
    text = json.dumps(view, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return "const CHASLES_VIEW = " + text + ";"


def assemble(view):
    parts = {
        "/*@CSS@*/": read(os.path.join(HERE, "viewer.css")),
        "/*@THREE@*/": read(THREE_JS),
        "/*@ORBIT@*/": read(ORBIT_JS),
        "/*@DATA@*/": data_script(view),
        "/*@VIEWER@*/": read(os.path.join(HERE, "viewer.js")),
    }
    out = []
    seen = set()
    for line in read(os.path.join(HERE, "template.html")).splitlines(keepends=True):
        key = line.strip()
        if key in parts:
            seen.add(key)
            out.append(parts[key] + "\n")
        else:
            out.append(line)
    missing = set(parts) - seen
    if missing:
        sys.exit("template.html lacks the placeholder line(s) " + ", ".join(sorted(missing)))
    return "".join(out)


# --------------------------------------------------------------------------------------------
# Kinematics: poses as (position [x, y, z], quaternion [w, x, y, z])
# --------------------------------------------------------------------------------------------

def quat_mul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw]


def rotate(q, v):
    w, x, y, z = q
    p = quat_mul(quat_mul(q, [0.0] + list(v)), [w, -x, -y, -z])
    return p[1:]


def axis_angle(axis, angle):
    s = math.sin(angle / 2)
    return [math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s]


def compose(a, b):
    """Pose a then pose b (b given in a's frame)."""
    pa, qa = a
    pb, qb = b
    r = rotate(qa, pb)
    return ([pa[0] + r[0], pa[1] + r[1], pa[2] + r[2]], quat_mul(qa, qb))


def flat(pose):
    p, q = pose
    return [round(v, 6) for v in p + q]


IDENTITY = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def chain_poses(joints, q):
    """World poses of a serial chain. joints[i] = (offset in the parent link, axis or None);
    returns one pose per link, link 0 the base at the origin."""
    poses = [IDENTITY]
    k = 0
    for offset, axis in joints:
        local = (list(offset), [1.0, 0.0, 0.0, 0.0])
        if axis is not None:
            local = (list(offset), axis_angle(axis, q[k]))
            k += 1
        poses.append(compose(poses[-1], local))
    return poses


def smooth(tau):
    """Minimum-jerk time scaling on [0, 1]."""
    tau = min(max(tau, 0.0), 1.0)
    return tau * tau * tau * (10 - 15 * tau + 6 * tau * tau)


def derivatives(fn, t, h=1e-4):
    """Value, first and second derivative of a vector function by central differences."""
    a, b, c = fn(t - h), fn(t), fn(t + h)
    return b, [(z - x) / (2 * h) for x, z in zip(a, c)], [(x - 2 * y + z) / (h * h) for x, y, z in zip(a, b, c)]


# --------------------------------------------------------------------------------------------
# The sample: a 3-joint arm swinging over a box of voxels on a table
# --------------------------------------------------------------------------------------------

AXIS_Y_POSE = [0, 0, 0, math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0]  # cylinder axis z -> y
AXIS_X_POSE = [0, 0, 0, math.cos(math.pi / 4), 0, math.sin(math.pi / 4), 0]  # z -> x


def with_position(pose, x, y, z):
    return [x, y, z] + pose[3:]


def sample_view():
    duration = 2.4
    frame_count = 200
    arm_joints = [((0, 0, 0.10), Z), ((0, 0, 0.25), Y), ((0.40, 0, 0), Y), ((0.34, 0, 0), None)]
    q_start, q_goal = [-0.7, -0.30, 1.05], [0.8, -0.25, 0.95]

    def q_of(t):
        s = smooth(t / duration)
        lift = -0.32 * math.sin(math.pi * s)  # raise the upper arm over the block midway
        return [q_start[0] + (q_goal[0] - q_start[0]) * s,
                q_start[1] + (q_goal[1] - q_start[1]) * s + lift,
                q_start[2] + (q_goal[2] - q_start[2]) * s - 0.6 * lift]

    links = [
        {"name": "base", "shapes": [
            {"type": "box", "size": [0.26, 0.26, 0.02], "pose": [0, 0, 0.01, 1, 0, 0, 0]},
            {"type": "cylinder", "radius": 0.09, "length": 0.08, "pose": [0, 0, 0.06, 1, 0, 0, 0]}],
         "spheres": [[0, 0, 0.05, 0.1]]},
        {"name": "column", "shapes": [
            {"type": "cylinder", "radius": 0.055, "length": 0.25, "pose": [0, 0, 0.125, 1, 0, 0, 0]}],
         "spheres": [[0, 0, 0.06, 0.06], [0, 0, 0.18, 0.06]]},
        {"name": "upper_arm", "shapes": [
            {"type": "cylinder", "radius": 0.065, "length": 0.13, "pose": AXIS_Y_POSE},
            {"type": "box", "size": [0.40, 0.07, 0.07], "pose": [0.2, 0, 0, 1, 0, 0, 0]}],
         "spheres": [[x, 0, 0, 0.055] for x in (0.0, 0.1, 0.2, 0.3, 0.4)]},
        {"name": "forearm", "shapes": [
            {"type": "cylinder", "radius": 0.05, "length": 0.11, "pose": AXIS_Y_POSE},
            {"type": "box", "size": [0.32, 0.055, 0.055], "pose": [0.16, 0, 0, 1, 0, 0, 0]}],
         "spheres": [[x, 0, 0, 0.045] for x in (0.0, 0.08, 0.16, 0.24, 0.32)]},
        {"name": "tool", "shapes": [
            {"type": "capsule", "radius": 0.022, "length": 0.05, "pose": with_position(AXIS_X_POSE, -0.02, 0, 0)},
            {"type": "sphere", "radius": 0.03, "pose": [0, 0, 0, 1, 0, 0, 0]}],
         "spheres": [[0, 0, 0, 0.035]]},
    ]
    trail_link = 4

    times = [duration * i / (frame_count - 1) for i in range(frame_count)]
    frames = []
    for t in times:
        poses = chain_poses(arm_joints, q_of(t))
        frames.append([v for pose in poses for v in flat(pose)])

    # a box of voxels on the table, under the middle of the swing
    voxel_size = 0.04
    centres = []
    for i in range(3):
        for j in range(3):
            for k in range(3):
                centres += [round(0.56 + 0.04 * i, 4), round(-0.04 + 0.04 * j, 4), round(0.17 + 0.04 * k, 4)]

    # the closest approach of the tool sphere to the voxels, as the checker would report it
    best = None
    for t in times:
        p = chain_poses(arm_joints, q_of(t))[trail_link][0]
        for c in range(0, len(centres), 3):
            centre = centres[c:c + 3]
            closest = [min(max(p[a], centre[a] - voxel_size / 2), centre[a] + voxel_size / 2) for a in range(3)]
            d = math.dist(p, closest) - 0.035
            if best is None or d < best[0]:
                best = (d, p, closest)
    clearance, p, closest = best
    marker_at = [round((a + b) / 2, 4) for a, b in zip(p, closest)]

    plot_t, plot_q, plot_qd, plot_qdd = [], [], [], []
    for t in times:
        q, qd, qdd = derivatives(q_of, t)
        plot_t.append(round(t, 6))
        plot_q.append([round(v, 5) for v in q])
        plot_qd.append([round(v, 5) for v in qd])
        plot_qdd.append([round(v, 4) for v in qdd])

    waypoints = [[round(v, 5) for v in chain_poses(arm_joints, q_of(t))[trail_link][0]]
                 for t in (0.0, duration / 2, duration)]

    return {
        "title": "Plan arm3_table — SUCCESS, %.2f s" % duration,
        "duration": duration,
        "robots": [{
            "name": "arm3",
            "links": links,
            "frames": {"t": [round(t, 6) for t in times], "poses": frames},
            "trail_link": trail_link,
            "waypoints": waypoints,
            "plot": {
                "joint_names": ["yaw", "shoulder", "elbow"],
                "t": plot_t, "q": plot_q, "qd": plot_qd, "qdd": plot_qdd,
                "max_velocity": [1.5, 1.5, 2.0],
                "max_acceleration": [4.0, 4.0, 5.0],
                "lower": [-2.9, -1.8, -0.2],
                "upper": [2.9, 1.8, 2.6],
            },
        }],
        "scene": {
            "objects": [
                {"name": "table", "shape": {"type": "box", "size": [0.5, 0.9, 0.04], "pose": [0.6, 0, 0.13, 1, 0, 0, 0]}},
                {"name": "table_leg", "shape": {"type": "cylinder", "radius": 0.03, "length": 0.11, "pose": [0.6, 0, 0.055, 1, 0, 0, 0]}},
            ],
            "voxels": [{"name": "octomap", "size": voxel_size, "centres": centres}],
        },
        "markers": [{"kind": "min_clearance", "position": marker_at,
                     "text": "min clearance %.3f m (tool – octomap)" % clearance}],
        "info": [
            "outcome SUCCESS",
            "planner RRTConnect, 38 ms planning, 3 waypoints",
            "trajectory %.2f s, %d frames" % (duration, frame_count),
            "verification: certified, min clearance %.3f m" % clearance,
        ],
    }


# --------------------------------------------------------------------------------------------
# Load test: 12-link snake, 10 s at 100 frames/s, 2000 plot points, optional voxels
# --------------------------------------------------------------------------------------------

def big_view(voxel_count):
    duration, rate, link_count = 10.0, 100, 12
    joints = [((0, 0, 0.1), Z)] + [((0.15, 0, 0), Y if i % 2 else Z) for i in range(link_count - 2)]
    n = len([j for j in joints if j[1] is not None])

    def q_of(t):
        return [0.5 * math.sin(0.6 * t + 0.4 * i) for i in range(n)]

    links = [{"name": "link%d" % i,
              "shapes": [{"type": "box", "size": [0.15, 0.05, 0.05], "pose": [0.075, 0, 0, 1, 0, 0, 0]},
                         {"type": "cylinder", "radius": 0.035, "length": 0.07, "pose": [0, 0, 0, 1, 0, 0, 0]}],
              "spheres": [[0.0375, 0, 0, 0.04], [0.1125, 0, 0, 0.04]]} for i in range(link_count)]
    times = [i / rate for i in range(int(duration * rate) + 1)]
    frames = [[v for pose in chain_poses(joints, q_of(t)) for v in flat(pose)] for t in times]
    plot_times = [duration * i / 1999 for i in range(2000)]
    samples = [derivatives(q_of, t) for t in plot_times]
    side = max(1, round(voxel_count ** (1 / 3)))
    centres = []
    for i in range(voxel_count):
        a, b, c = i % side, (i // side) % side, i // (side * side)
        centres += [round(1.0 + 0.02 * a, 3), round(-0.5 + 0.02 * b, 3), round(0.01 + 0.02 * c, 3)]
    return {
        "title": "Load test — %d links, %d frames, %d voxels" % (link_count, len(times), voxel_count),
        "duration": duration,
        "robots": [{
            "name": "snake", "links": links,
            "frames": {"t": times, "poses": frames},
            "trail_link": link_count - 1,
            "waypoints": [],
            "plot": {"joint_names": ["j%d" % i for i in range(n)], "t": plot_times,
                     "q": [s[0] for s in samples], "qd": [s[1] for s in samples], "qdd": [s[2] for s in samples],
                     "max_velocity": [1.0] * n, "max_acceleration": [1.0] * n,
                     "lower": [-1.0] * n, "upper": [1.0] * n},
        }],
        "scene": {"objects": [], "voxels": [{"name": "map", "size": 0.02, "centres": centres}] if voxel_count else []},
        "markers": [],
        "info": ["synthetic load test"],
    }


def readable_json(value, indent=""):
    """JSON with objects and lists of lists indented, and lists of plain values on one line."""
    inner = indent + "  "
    if isinstance(value, dict):
        items = [inner + json.dumps(k, ensure_ascii=False) + ": " + readable_json(v, inner) for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}" if items else "{}"
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return "[\n" + ",\n".join(inner + readable_json(v, inner) for v in value) + "\n" + indent + "]"
    return json.dumps(value, ensure_ascii=False, separators=(", ", ": "))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", nargs="?", help="HTML file to write")
    parser.add_argument("--view", default=SAMPLE, help="view JSON (default sample_view.json)")
    parser.add_argument("--big", action="store_true", help="generated load-test view instead of --view")
    parser.add_argument("--voxels", type=int, default=0, help="voxels in the --big view")
    parser.add_argument("--regenerate", action="store_true", help="rewrite sample_view.json")
    args = parser.parse_args()

    if args.regenerate:
        with open(SAMPLE, "w", encoding="utf-8") as f:
            f.write(readable_json(sample_view()) + "\n")
        print("wrote", SAMPLE)
    if not args.out:
        if not args.regenerate:
            parser.error("give OUT.html or --regenerate")
        return
    if args.big:
        view = big_view(args.voxels)
    else:
        with open(args.view, encoding="utf-8") as f:
            view = json.load(f)
    with open(args.out, "w", encoding="utf-8") as f:
        f.write(assemble(view))
    print("wrote", args.out)


if __name__ == "__main__":
    main()
