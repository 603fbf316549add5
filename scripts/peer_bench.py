#!/usr/bin/env python3
"""Times a peer scan matcher on the scan pairs `cargo bench -p plumbline --bench matching` wrote.

Peer: small_gicp (PyPI `small_gicp`), single thread, on the same pairs with an identity initial
guess. 2-D scans are extruded to three layers (z = -0.1, 0, 0.1 m) so point-to-plane ICP sees
walls as planes; plain point-to-point ICP runs on the same points. The time is one whole
`align` call per pair: preprocessing (k-d tree, normals) plus registration, like the Plumbline
figure, which includes preparing the reference scan.

    pip install small_gicp numpy
    python3 scripts/peer_bench.py target/bench-pairs/mit-csail-361.txt
"""
import json
import sys
import time

import numpy as np
import small_gicp


def pairs(path):
    with open(path) as f:
        lines = [l.split() for l in f]
    for a, b in zip(lines[0::2], lines[1::2]):
        yield (np.array(a, dtype=float).reshape(-1, 2), np.array(b, dtype=float).reshape(-1, 2))


def extrude(p):
    layers = [np.hstack([p, np.full((len(p), 1), z)]) for z in (-0.1, 0.0, 0.1)]
    return np.vstack(layers)


def time_peer(path, registration_type, repeats=5):
    times, fails = [], 0
    for ref, cur in pairs(path):
        target, source = extrude(ref), extrude(cur)
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            result = small_gicp.align(
                target,
                source,
                registration_type=registration_type,
                downsampling_resolution=0.01,
                max_correspondence_distance=0.5,
                num_threads=1,
            )
            best = min(best, time.perf_counter() - t0)
        fails += not result.converged
        times.append(best * 1e6)
    times.sort()
    pick = lambda p: times[min(len(times) - 1, max(0, int(np.ceil(len(times) * p)) - 1))]
    return {"peer": f"small_gicp {registration_type}", "pairs": path, "median_us": round(pick(0.5), 1),
            "p99_us": round(pick(0.99), 1), "not_converged": fails, "n": len(times)}


if __name__ == "__main__":
    for path in sys.argv[1:]:
        for kind in ("PLANE_ICP", "ICP"):
            print(json.dumps(time_peer(path, kind)))
