#!/usr/bin/env python3
"""Where a simulated survey map's error lies: the occupied cells of `plumbline slam --map PREFIX`
placed in the world by the first true pose (as `map_error_m` places them), each scored by its
distance to the nearest wall, then summed by distance band and by 2 m region, largest share
first. A shift of the whole map shows as every band above a cell or two; a person walking
through the survey shows as one region of cells a metre or more from any wall.

    plumbline slam D/scans.clf --lidar xv11 --world office --truth D/truth.txt --map D/m
    python3 scripts/map_error_cells.py D/m crates/sim/worlds/office.world D/truth.txt
"""
import math
import re
import sys
from collections import defaultdict


def walls(path):
    """The wall segments of a world file's `outline`, `wall` and `box` lines."""
    segments = []
    with open(path) as f:
        for line in f:
            fields = line.split("#")[0].split()
            if not fields or fields[0] not in ("outline", "wall", "box"):
                continue
            v = list(map(float, fields[1:]))
            if fields[0] == "wall":
                segments.append(v)
            elif fields[0] == "box":
                x0, y0, x1, y1 = v
                corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
                segments += [[*corners[i], *corners[(i + 1) % 4]] for i in range(4)]
            else:
                corners = list(zip(v[0::2], v[1::2]))
                segments += [[*corners[i], *corners[(i + 1) % len(corners)]] for i in range(len(corners))]
    return segments


def distance(px, py, segment):
    ax, ay, bx, by = segment
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def occupied_cells(prefix):
    """Centres of the occupied (black) cells of PREFIX.pgm in the map frame."""
    yaml = open(prefix + ".yaml").read()
    resolution = float(re.search(r"resolution: ([\d.eE+-]+)", yaml).group(1))
    ox, oy = map(float, re.search(r"origin: \[([^\]]+)\]", yaml).group(1).split(",")[:2])
    data = open(prefix + ".pgm", "rb").read()
    magic, size, _maxval, pixels = data.split(b"\n", 3)
    if magic != b"P5":
        sys.exit(f"{prefix}.pgm: not a binary PGM")
    width, height = map(int, size.split())
    for row in range(height):
        for col in range(width):
            if pixels[row * width + col] == 0:
                yield ox + (col + 0.5) * resolution, oy + (height - 1 - row + 0.5) * resolution


def main(argv):
    if len(argv) != 4:
        sys.exit(__doc__)
    prefix, world, truth = argv[1:]
    segments = walls(world)
    _, x0, y0, th0 = map(float, open(truth).readline().split())
    c, s = math.cos(th0), math.sin(th0)
    cells = []
    for mx, my in occupied_cells(prefix):
        x, y = c * mx - s * my + x0, s * mx + c * my + y0
        cells.append((x, y, min(distance(x, y, seg) for seg in segments)))
    if not cells:
        sys.exit(f"{prefix}.pgm: no occupied cell")
    total = sum(e for _, _, e in cells)
    print(f"occupied cells {len(cells)}, mean distance to a wall {total / len(cells):.3f} m")
    for lo, hi in [(0, 0.05), (0.05, 0.1), (0.1, 0.2), (0.2, 0.5), (0.5, 1.0), (1.0, math.inf)]:
        band = [e for _, _, e in cells if lo <= e < hi]
        print(f"  {lo:.2f}-{hi:.2f} m: {len(band):5d} cells, {sum(band) / total:5.1%} of the error")
    regions = defaultdict(lambda: [0, 0.0])
    for x, y, e in cells:
        r = regions[(2 * math.floor(x / 2), 2 * math.floor(y / 2))]
        r[0] += 1
        r[1] += e
    for (rx, ry), (n, err) in sorted(regions.items(), key=lambda kv: -kv[1][1])[:8]:
        print(f"  x {rx}..{rx + 2} y {ry}..{ry + 2}: {n:4d} cells, mean {err / n:.3f} m, {err / total:5.1%} of the error")


if __name__ == "__main__":
    main(sys.argv)
