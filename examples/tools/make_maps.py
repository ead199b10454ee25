#!/usr/bin/env python3
"""Writes the primitive sources of the mobile-robot maps: examples/scenes/maze.json, office.json,
drone_course.json and pillar_room.json (a seeded maze; fixed office, drone-course and room layouts). Voxelise them with
chasles-scene-to-octomap as examples/scenes/README.md shows.

Usage: python3 examples/tools/make_maps.py OUT_DIR   (e.g. examples/scenes)"""
import json
import random
import sys
# 6 x 6 cells; wall centre lines on 0.1 + 0.2 k (grown by the voxeliser, a 0.1 m wall fills
# whole 0.2 m octree nodes); cell pitches 1.2 / 1.4 m: corridors 1.1 / 1.3 m clear (1.0 / 1.2 m
# after the voxeliser's growth).
PITCH = [1.2, 1.4, 1.2, 1.4, 1.4, 1.2]
N = len(PITCH)
T, H = 0.1, 0.6   # wall thickness, height
c = [0.1]
for p in PITCH: c.append(round(c[-1] + p, 6))
def maze(seed):
    rnd = random.Random(seed)
    # passages: set of frozenset((cell a, cell b))
    open_ = set(); seen = {(0, 0)}; stack = [(0, 0)]
    while stack:
        x, y = stack[-1]
        nb = [(x+dx, y+dy) for dx, dy in ((1,0),(-1,0),(0,1),(0,-1)) if 0 <= x+dx < N and 0 <= y+dy < N and (x+dx, y+dy) not in seen]
        if not nb: stack.pop(); continue
        n = rnd.choice(nb); open_.add(frozenset(((x, y), n))); seen.add(n); stack.append(n)
    return open_
def solve(open_):
    prev = {(0,0): None}; q = [(0,0)]
    for cur in q:
        x, y = cur
        for n in ((x+1,y),(x-1,y),(x,y+1),(x,y-1)):
            if n not in prev and frozenset((cur, n)) in open_: prev[n] = cur; q.append(n)
    p = [(N-1, N-1)]
    while prev[p[-1]] is not None: p.append(prev[p[-1]])
    return p[::-1]
def turns(p):
    t = 0
    for a, b, d in zip(p, p[1:], p[2:]):
        if (b[0]-a[0], b[1]-a[1]) != (d[0]-b[0], d[1]-b[1]): t += 1
    return t
def draw(open_, path=()):
    rows = []
    for y in reversed(range(N)):
        top = "+"; mid = "|"
        for x in range(N):
            top += ("   " if (y < N-1 and frozenset(((x,y),(x,y+1))) in open_) else "---") + "+"
            mid += (" * " if (x,y) in path else "   ") + (" " if (x < N-1 and frozenset(((x,y),(x+1,y))) in open_) else "|")
        rows += [top, mid]
    rows.append("+" + "---+" * N)
    return "\n".join(rows)
def r(v): return round(v, 6)
def pose(x, y, z): return {"position": {"x": r(x), "y": r(y), "z": r(z)}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}
def box(name, x0, x1, y0, y1, z0, z1):
    return {"name": name, "size": {"x": r(x1-x0), "y": r(y1-y0), "z": r(z1-z0)}, "pose": pose((x0+x1)/2, (y0+y1)/2, (z0+z1)/2)}
def cyl(name, x, y, radius, z0, z1):
    return {"name": name, "radius": radius, "length": r(z1-z0), "pose": pose(x, y, (z0+z1)/2)}

def maze_scene():
    m = maze(14)
    boxes = []
    # walls along x on line y = c[j]
    for j in range(N + 1):
        present = [j in (0, N) or frozenset(((x, j-1), (x, j))) not in m for x in range(N)]
        x = 0
        while x < N:
            if not present[x]: x += 1; continue
            a = x
            while x < N and present[x]: x += 1
            boxes.append(box(f"wall_y{j}_{a}_{x}", c[a]-T/2, c[x]+T/2, c[j]-T/2, c[j]+T/2, 0, H))
    for i in range(N + 1):
        present = [i in (0, N) or frozenset(((i-1, y), (i, y))) not in m for y in range(N)]
        y = 0
        while y < N:
            if not present[y]: y += 1; continue
            a = y
            while y < N and present[y]: y += 1
            boxes.append(box(f"wall_x{i}_{a}_{y}", c[i]-T/2, c[i]+T/2, c[a]-T/2, c[y]+T/2, 0, H))
    return {"boxes": boxes}

def office_scene():
    # Walls 0.1 m thick on lines 0.1 + 0.2 k: grown by the voxeliser (one 0.05 m voxel each side)
    # they fill whole 0.2 m octree nodes, which keeps the pruned map small.
    T, H = 0.1, 2.5
    boxes, cyls = [], []
    def wall(name, x0, x1, y0, y1): boxes.append(box(name, x0, x1, y0, y1, 0, H))
    # outer walls on the lines x = 0.1, 11.9 and y = 0.1, 7.9
    wall("outer_south", 0.05, 11.95, 0.05, 0.15); wall("outer_north", 0.05, 11.95, 7.85, 7.95)
    wall("outer_west", 0.05, 0.15, 0.05, 7.95); wall("outer_east", 11.85, 11.95, 0.05, 7.95)
    # corridor along the middle, clear y in [3.15, 4.85], open along its whole length;
    # its walls (y = 3.1, 4.9) have 1.0 m door gaps
    def corridor_wall(name, yc, doors):
        x = 0.15
        for k, (d0, d1) in enumerate(doors + [(11.85, 11.85)]):
            if d0 > x: wall(f"{name}_{k}", x, d0, yc-T/2, yc+T/2)
            x = d1
    corridor_wall("corridor_south", 3.1, [(2.5, 3.5), (8.0, 9.0)])
    corridor_wall("corridor_north", 4.9, [(1.5, 2.5), (9.0, 10.0)])
    # room dividers (x = 6.1 south, 5.1 north)
    wall("divider_south", 6.05, 6.15, 0.15, 3.05)
    wall("divider_north", 5.05, 5.15, 4.95, 7.85)
    # desks 1.6 x 0.8 x 0.75 (long side along x or y); chairs: cylinders r 0.25, 0.9 m tall
    def desk(name, x, y, along_x=True):
        sx, sy = (1.6, 0.8) if along_x else (0.8, 1.6)
        boxes.append(box(name, x-sx/2, x+sx/2, y-sy/2, y+sy/2, 0, 0.75))
    def chair(name, x, y): cyls.append(cyl(name, x, y, 0.25, 0, 0.9))
    # south-west room (x 0.15..6.05, y 0.15..3.05), door x 2.5..3.5
    desk("desk_sw_0", 1.0, 1.2, along_x=False); chair("chair_sw_0", 1.7, 1.2)
    desk("desk_sw_1", 4.8, 0.6); chair("chair_sw_1", 4.8, 1.35)
    # south-east room (x 6.15..11.85, y 0.15..3.05), door x 8.0..9.0; goal (10.5, 1.5)
    desk("desk_se_0", 7.1, 0.6); chair("chair_se_0", 7.1, 1.35)
    # north-west room (x 0.15..5.05, y 4.95..7.85), door x 1.5..2.5
    desk("desk_nw_0", 3.8, 7.4); chair("chair_nw_0", 3.8, 6.65)
    desk("desk_nw_1", 0.6, 6.9, along_x=False); chair("chair_nw_1", 1.35, 6.9)
    # north-east room (x 5.15..11.85, y 4.95..7.85), door x 9.0..10.0: a meeting table, a desk
    desk("table_ne", 8.0, 6.6); chair("chair_ne_0", 7.5, 7.25); chair("chair_ne_1", 7.6, 5.95)
    desk("desk_ne_1", 11.4, 6.4, along_x=False)
    return {"boxes": boxes, "cylinders": cyls}

def drone_scene():
    boxes, cyls = [], []
    # wall across the middle (x = 5, 0.2 m thick), full height, window 1.2 x 1.2 centred (y 5, z 2)
    x0, x1 = 4.9, 5.1
    boxes.append(box("wall_south", x0, x1, 0, 4.4, 0, 4))
    boxes.append(box("wall_north", x0, x1, 5.6, 10, 0, 4))
    boxes.append(box("wall_below_window", x0, x1, 4.4, 5.6, 0, 1.4))
    boxes.append(box("wall_above_window", x0, x1, 4.4, 5.6, 2.6, 4))
    # overhead beam across the course (along y) at x = 7.5, z 3.0..3.4
    boxes.append(box("beam", 7.3, 7.7, 0, 10, 3.0, 3.4))
    for k, (x, y) in enumerate([(2.5, 2.5), (3.0, 5.0), (2.5, 7.5), (7.0, 3.5), (7.5, 7.0), (8.5, 1.5), (6.5, 5.8)]):
        cyls.append(cyl(f"pillar_{k}", x, y, 0.3, 0, 4))
    return {"boxes": boxes, "cylinders": cyls}

def pillar_room_scene():
    # An 8 m x 8 m room for the four-base swap (examples/requests/make_coordination.py): outer walls
    # 0.1 m thick on the lines 0.1 and 7.9 (like the maze), 1.0 m tall; four pillars r 0.25 m
    # outside the 3 m square whose corners the bases swap, one beside the middle of each side.
    boxes, cyls = [], []
    H = 1.0
    boxes.append(box("outer_south", 0.05, 7.95, 0.05, 0.15, 0, H))
    boxes.append(box("outer_north", 0.05, 7.95, 7.85, 7.95, 0, H))
    boxes.append(box("outer_west", 0.05, 0.15, 0.15, 7.85, 0, H))
    boxes.append(box("outer_east", 7.85, 7.95, 0.15, 7.85, 0, H))
    for k, (x, y) in enumerate([(4.0, 1.4), (6.6, 4.0), (4.0, 6.6), (1.4, 4.0)]):
        cyls.append(cyl(f"pillar_{k}", x, y, 0.25, 0, H))
    return {"boxes": boxes, "cylinders": cyls}

out = sys.argv[1] if len(sys.argv) > 1 else "examples/scenes"
for name, scene in [("maze", maze_scene()), ("office", office_scene()), ("drone_course", drone_scene()),
                    ("pillar_room", pillar_room_scene())]:
    with open(f"{out}/{name}.json", "w") as f:
        json.dump(scene, f, indent=2); f.write("\n")
    print(name, len(scene.get("boxes", [])), "boxes", len(scene.get("cylinders", [])), "cylinders")
