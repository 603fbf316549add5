#!/usr/bin/env python3
"""Turns a simulated flight (`plumbline sim ... --out DIR`) into the golden replay's inputs:
what the onboard stack is handed at each 500 Hz step. Numbers are copied as the simulator wrote
them, so the replay parses exactly these values.
    python3 scripts/golden_inputs.py DIR "COMMAND THAT MADE DIR" > crates/core/tests/golden/inputs.txt
"""
import sys

STEP_S = 0.002
# The pilot's commands: arm at 0.5 s (as the simulator's scenarios do), the kill switch at 2.9 s.
PILOT = [(0.5, "pilot 1 0 0 0 0 0 0"), (2.9, "pilot 1 0 1 0 0 0 0")]


def rows(path):
    with open(path) as f:
        next(f)  # header
        return [line.strip().split(",") for line in f if line.strip()]


def main(out_dir, command):
    imu = rows(f"{out_dir}/imu.csv")
    sonar = rows(f"{out_dir}/sonar.csv")
    scans = []
    with open(f"{out_dir}/scans.clf") as f:
        for line in f:
            v = line.split()
            if not v or v[0] != "ROBOTLASER1":
                continue
            start, step, max_range, n = v[2], v[4], float(v[5]), int(v[8])
            ranges = ["-" if float(r) >= max_range else r for r in v[9 : 9 + n]]
            scans.append((float(v[-3]), v[-3], start, step, ranges))
    steps = round(float(imu[-1][0]) / STEP_S)
    print("# Golden replay inputs: what the onboard stack is handed at each step")
    print("# (crates/core/tests/golden_replay.rs; regenerate with `bash scripts/golden.sh inputs`).")
    print(f"# Recorded from: {command}")
    print("# step T_S DT_S GYRO_X GYRO_Y GYRO_Z ACCEL_X ACCEL_Y ACCEL_Z  (the lines after it belong to it)")
    print("# sonar T_S RANGE_M")
    print("# pilot ARM MANUAL KILL ROLL PITCH YAW THROTTLE  (held until the next pilot line)")
    print("# scan STAMP_S START_RAD STEP_RAD BEAM_DT_S R1..RN  (a completed revolution; - is no return)")
    i = s = c = p = 0
    for k in range(1, steps + 1):
        t = k * STEP_S
        while i + 1 < len(imu) and float(imu[i + 1][0]) <= t + 1e-9:
            i += 1
        print(f"step {t:.6f} {STEP_S} " + " ".join(imu[i][1:7]))
        while s < len(sonar) and float(sonar[s][0]) <= t + 1e-9:
            # Only the newest reading of a step is handed over.
            if s + 1 == len(sonar) or float(sonar[s + 1][0]) > t + 1e-9:
                print(f"sonar {sonar[s][0]} {sonar[s][1]}")
            s += 1
        while p < len(PILOT) and PILOT[p][0] <= t + 1e-9:
            print(PILOT[p][1])
            p += 1
        # A revolution is complete when the next one starts (the last: one period later).
        while c < len(scans):
            stamp, text, start, step, ranges = scans[c]
            period = (scans[c + 1][0] if c + 1 < len(scans) else stamp + period_last(scans)) - stamp
            if stamp + period > t + 1e-9:
                break
            print(f"scan {text} {start} {step} {period / len(ranges):.9f} " + " ".join(ranges))
            c += 1


def period_last(scans):
    return scans[-1][0] - scans[-2][0]


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
