#!/usr/bin/env python3
"""An external planner for closed-loop runs (docs/planner-protocol.md) that reads the map's .npy layers.

    oeg run SCENARIO --planner-command "python3 examples/planners/npy_planner.py"

It reads decisions.npy through layers.json, treats free and traversable cells as drivable, keeps the robot's
centre `INFLATION_M` from anything else that was observed, and runs a breadth-first search over 8-connected
cells (a plain Dijkstra with unit and sqrt(2) steps). Never-observed cells are drivable, as a robot that
explores plans through what it has not seen. numpy is used when installed; without it the .npy files are read
with the standard library. Exit 3 says that there is no path.
"""

import ast
import heapq
import json
import math
import struct
import sys
from pathlib import Path

# The Pioneer 3-AT's circumscribed radius (0.346 m) and half a 0.05 m cell's diagonal: the built-in planner's
# default while navigating (the footprint meets cells' squares, the inflation is measured between centres).
INFLATION_M = 0.381
UNKNOWN, FREE, TRAVERSABLE = 0, 1, 2


def read_npy(path):
    """A 2D array of a .npy file as a list of rows (numpy's format 1.0, C order, uint8 or float32)."""
    data = Path(path).read_bytes()
    if data[:6] != b"\x93NUMPY":
        raise ValueError(f"{path}: not a .npy file")
    header_len = struct.unpack("<H", data[8:10])[0]
    header = ast.literal_eval(data[10 : 10 + header_len].decode("latin1"))
    rows, cols = header["shape"]
    body = data[10 + header_len :]
    fmt = {"|u1": "B", "<f4": "f"}[header["descr"]]
    values = struct.unpack(f"<{rows * cols}{fmt}", body)
    return [list(values[r * cols : (r + 1) * cols]) for r in range(rows)]


def main(argv):
    if len(argv) != 8:
        print(f"usage: {argv[0]} START_X START_Y GOAL_X GOAL_Y MAP_YAML LAYERS_JSON PATH_CSV", file=sys.stderr)
        return 2
    sx, sy, gx, gy = (float(v) for v in argv[1:5])
    layers_json, path_csv = Path(argv[6]), Path(argv[7])
    meta = json.loads(layers_json.read_text())
    res = meta["resolution_m"]
    x0, y0 = meta["origin_xy_m"]
    grid = read_npy(layers_json.parent / meta["layers"]["decisions"]["file"])
    rows, cols = len(grid), len(grid[0])

    def cell(x, y):
        c = min(max(int(math.floor((x - x0) / res)), 0), cols - 1)
        r = min(max(int(math.floor((y - y0) / res)), 0), rows - 1)
        return r, c

    # Obstacles: observed cells that are neither free nor traversable; inflated by INFLATION_M.
    reach = int(math.ceil(INFLATION_M / res))
    offsets = [(dr, dc) for dr in range(-reach, reach + 1) for dc in range(-reach, reach + 1)
               if math.hypot(dr, dc) * res <= INFLATION_M]
    blocked = [[False] * cols for _ in range(rows)]
    for r in range(rows):
        for c in range(cols):
            if grid[r][c] not in (UNKNOWN, FREE, TRAVERSABLE):
                for dr, dc in offsets:
                    if 0 <= r + dr < rows and 0 <= c + dc < cols:
                        blocked[r + dr][c + dc] = True
    start, goal = cell(sx, sy), cell(gx, gy)
    # The robot stands where it is: the cells under it are not obstacles to leaving.
    for dr, dc in offsets:
        r, c = start[0] + dr, start[1] + dc
        if 0 <= r < rows and 0 <= c < cols and grid[r][c] in (UNKNOWN, FREE, TRAVERSABLE):
            blocked[r][c] = False
    if blocked[goal[0]][goal[1]]:
        return 3
    cost = {start: 0.0}
    parent = {}
    heap = [(0.0, start)]
    while heap:
        d, here = heapq.heappop(heap)
        if here == goal:
            break
        if d > cost[here]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nxt = (here[0] + dr, here[1] + dc)
                if (dr, dc) == (0, 0) or not (0 <= nxt[0] < rows and 0 <= nxt[1] < cols):
                    continue
                if blocked[nxt[0]][nxt[1]]:
                    continue
                nd = d + math.hypot(dr, dc)
                if nd < cost.get(nxt, math.inf):
                    cost[nxt], parent[nxt] = nd, here
                    heapq.heappush(heap, (nd, nxt))
    if goal not in cost:
        return 3
    cells = [goal]
    while cells[-1] != start:
        cells.append(parent[cells[-1]])
    cells.reverse()
    lines = ["x_m,y_m"] + [f"{x0 + (c + 0.5) * res},{y0 + (r + 0.5) * res}" for r, c in cells]
    lines[-1] = f"{gx},{gy}"
    path_csv.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
