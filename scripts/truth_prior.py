#!/usr/bin/env python3
"""Writes a simulated survey log whose robot pose (the odometry field of ROBOTLASER1) is the
simulator's true pose, optionally with a velocity error, so that `plumbline slam --odom-prior`
runs with a motion prior of known quality: the best any prior (wheel odometry, an IMU) could
give the SLAM, and how much a given velocity error costs.

The velocity error is a first-order Gauss-Markov process per world axis (standard deviation
SIGMA m/s, correlation time TAU s), the shape of the velocity error a filter that integrates
an IMU between lidar fixes leaves; it is integrated into the position.

    python3 scripts/truth_prior.py D/scans.clf D/truth.txt OUT.clf [SIGMA TAU SEED]
    plumbline slam OUT.clf --odom-prior --lidar xv11 --world W --truth D/truth.txt --json
"""
import math
import random
import sys


def main(argv):
    if len(argv) not in (4, 7):
        sys.exit(__doc__)
    log, truth, out = argv[1:4]
    sigma, tau, seed = (float(argv[4]), float(argv[5]), int(argv[6])) if len(argv) == 7 else (0.0, 1.0, 0)
    poses = {}
    with open(truth) as f:
        for n, line in enumerate(f, 1):
            fields = line.split()
            if len(fields) != 4:
                sys.exit(f"{truth}:{n}: expected `t x y theta`, found {len(fields)} fields")
            t, x, y, th = map(float, fields)
            poses[round(t, 3)] = (x, y, th)
    rng = random.Random(seed)
    err, vel, last_t = [0.0, 0.0], [0.0, 0.0], None
    with open(log) as src, open(out, "w") as dst:
        for n, line in enumerate(src, 1):
            fields = line.split()
            if fields and fields[0] == "ROBOTLASER1":
                t = float(fields[-1])
                pose = poses.get(round(t, 3))
                if pose is None:
                    sys.exit(f"{log}:{n}: no true pose at {t} s in {truth}: is it the same run?")
                if last_t is not None and sigma > 0.0:
                    dt = t - last_t
                    keep = math.exp(-dt / tau)
                    kick = sigma * math.sqrt(1.0 - keep * keep)
                    for k in range(2):
                        vel[k] = keep * vel[k] + kick * rng.gauss(0.0, 1.0)
                        err[k] += vel[k] * dt
                last_t = t
                # The robot pose is the 11th to 9th field from the end (DESIGN.md §5).
                fields[-11:-8] = [f"{pose[0] + err[0]:.6f}", f"{pose[1] + err[1]:.6f}", f"{pose[2]:.6f}"]
                line = " ".join(fields) + "\n"
            dst.write(line)


if __name__ == "__main__":
    main(sys.argv)
