#!/usr/bin/env python3
"""pymavlink as the autopilot beside `plumbline companion`: it streams its own estimate back while
the companion replays a lidar log, and checks that the SLAM took its motion guess from it.

usage: companion_autopilot.py PLUMBLINE_BINARY SCRATCH_DIR CASE

The log is made here: a vehicle sliding sideways (to its left) at 0.5 m/s between two walls, one
ahead and one behind, that run on past the lidar's reach. Every revolution looks the same, so the
scans alone cannot tell how far it went: only the autopilot's estimate can. The autopilot faces
0.8 rad east of its north, so its NED frame is neither the companion's map frame nor a mirror of
it, and a sign or rotation slip in the conversion sends the guess off the corridor's axis.

CASE is one of
    position   LOCAL_POSITION_NED with ATTITUDE at 50 Hz: the companion's pose follows the motion
    odometry   ODOMETRY at 50 Hz: the same
    silent     the autopilot sends nothing: no guess, and the pose does not follow
    hostile    silence, NaN fields, a failed ODOMETRY, a reboot (time_boot_ms back to 0) and
               garbage: each counted as the companion's summary says, guesses before and after

The replay runs at the pace of its stamps (`--realtime`); the autopilot's clock starts when the
companion's first HEARTBEAT (sent as it takes the first revolution) arrives. Exits non-zero,
saying what was wrong, on the first failed check.
"""
import json
import math
import os
import random
import socket
import subprocess
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import common as mavlink  # noqa: E402
from peer_socket import loopback_socket  # noqa: E402

RATE_HZ = 5.0
SPEED_M_S = 1.2
WALL_M = 1.2
MAX_RANGE_M = 8.0
# Posts on both walls every PERIOD_M: a revolution's motion (SPEED_M_S / RATE_HZ = 0.24 m) looks
# the same as 0.16 m the other way, which is nearer a guess of no motion.
PERIOD_M = 0.4
POST_WIDTH_M = 0.15
POST_DEPTH_M = 0.08
HEADING_NED = 0.8
START_NED = (3.0, -2.0)


def fail(why):
    print(f"companion_autopilot: {why}", file=sys.stderr)
    sys.exit(1)


def corridor(y0):
    """Wall segments near a lidar at (0, y0), in its own frame (x ahead, y left)."""
    segs = [((WALL_M, -50.0), (WALL_M, 50.0)), ((-WALL_M, -50.0), (-WALL_M, 50.0))]
    k0 = math.floor((y0 - MAX_RANGE_M) / PERIOD_M)
    for k in range(k0, k0 + int(2 * MAX_RANGE_M / PERIOD_M) + 2):
        a, b = k * PERIOD_M - POST_WIDTH_M / 2 - y0, k * PERIOD_M + POST_WIDTH_M / 2 - y0
        for side in (1.0, -1.0):
            face, wall = side * (WALL_M - POST_DEPTH_M), side * WALL_M
            segs += [((face, a), (face, b)), ((face, a), (wall, a)), ((face, b), (wall, b))]
    return segs


def cast(segs, angle):
    dx, dy = math.cos(angle), math.sin(angle)
    best = MAX_RANGE_M
    for (x1, y1), (x2, y2) in segs:
        ex, ey = x2 - x1, y2 - y1
        den = dx * ey - dy * ex
        if abs(den) < 1e-12:
            continue
        t = (x1 * ey - y1 * ex) / den
        u = (x1 * dy - y1 * dx) / den
        if 0.0 < t < best and 0.0 <= u <= 1.0:
            best = t
    return best


def write_log(path, seconds):
    """The corridor log: ROBOTLASER1 lines, 360 beams, the lidar sliding left."""
    n = 360
    inc = 2 * math.pi / n
    start = -math.pi
    with open(path, "w") as f:
        for k in range(int(seconds * RATE_HZ)):
            t = k / RATE_HZ
            segs = corridor(SPEED_M_S * t)
            ranges = [cast(segs, start + i * inc) for i in range(n)]
            f.write(f"ROBOTLASER1 0 {start:.6f} {inc * (n - 1):.6f} {inc:.6f} {MAX_RANGE_M} 0.010 0 {n} ")
            f.write(" ".join(f"{r:.3f}" for r in ranges))
            f.write(f" 0 0 0 0 0 0 0 0 0 0 0 0 {1000 + t:.6f} corridor {1000 + t:.6f}\n")


def truth_ned(t):
    """Position (north, east) and heading of the vehicle `t` seconds into the log."""
    # Sliding left in the body (FRD y negative) at the speed, the heading held.
    vn, ve = SPEED_M_S * math.sin(HEADING_NED), -SPEED_M_S * math.cos(HEADING_NED)
    return START_NED[0] + vn * t, START_NED[1] + ve * t


def quaternion(yaw):
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


class Autopilot:
    def __init__(self, sock):
        self.sock = sock
        self.mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.peer = None

    def send(self, msg):
        if self.peer is not None:
            self.sock.sendto(msg.pack(self.mav), self.peer)

    def position(self, boot_ms, north, east):
        self.send(mavlink.MAVLink_local_position_ned_message(boot_ms, north, east, -1.0, 0, 0, 0))
        self.send(mavlink.MAVLink_attitude_message(boot_ms, 0.01, -0.02, HEADING_NED, 0, 0, 0))

    def odometry(self, boot_ms, north, east, quality=100, reset=0):
        nan = float("nan")
        self.send(mavlink.MAVLink_odometry_message(
            boot_ms * 1000, mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_BODY_FRD,
            north, east, -1.0, quaternion(HEADING_NED), 0, 0, 0, 0, 0, 0,
            [nan] + [0.0] * 20, [nan] + [0.0] * 20, reset,
            mavlink.MAV_ESTIMATOR_TYPE_NAIVE, quality))


def hostile(ap, t, boot_ms):
    """The autopilot misbehaving, phase by phase, `t` seconds into the replay."""
    north, east = truth_ned(t)
    if t < 1.5:
        ap.position(boot_ms, north, east)
    elif t < 3.5:
        pass  # silent: stale
    elif t < 4.5:
        ap.position(boot_ms, float("nan"), east)  # NaN north: invalid
    elif t < 5.0:
        ap.odometry(boot_ms, north, east, quality=-1)  # the estimate failed: invalid
    else:
        # Rebooted at 5 s: its clock starts again and its origin is elsewhere; garbage for a
        # while after.
        ap.position(int((t - 5.0) * 1000), north - 10.0, east + 4.0)
        if t < 6.5 and random.random() < 0.1:
            ap.sock.sendto(bytes(random.getrandbits(8) for _ in range(40)), ap.peer)


def main():
    binary, scratch, case = sys.argv[1], sys.argv[2], sys.argv[3]
    random.seed(7)
    seconds = 8.0 if case == "hostile" else 4.0
    log = os.path.join(scratch, f"corridor-{case}.clf")
    write_log(log, seconds)
    sock, port = loopback_socket(0.005)
    child = subprocess.Popen(
        [binary, "companion", "--replay-log", log, "--realtime",
         "--mavlink", f"udpout:127.0.0.1:{port}", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ap = Autopilot(sock)
    parser = mavlink.MAVLink(None)
    odometry = []
    started = None
    next_send = 0.0
    quiet_since = None
    while True:
        try:
            data, addr = sock.recvfrom(4096)
            quiet_since = None
            for m in parser.parse_buffer(data) or []:
                if m.get_type() == "HEARTBEAT" and started is None:
                    started, ap.peer = time.monotonic(), addr
                elif m.get_type() == "ODOMETRY":
                    odometry.append(m)
        except socket.timeout:
            if child.poll() is not None:
                quiet_since = quiet_since or time.monotonic()
                if time.monotonic() - quiet_since > 0.5:
                    break
        now = time.monotonic()
        if started is None or child.poll() is not None or now < next_send:
            continue
        next_send = now + 0.02
        t = now - started
        boot_ms = int(60_000 + t * 1000)
        north, east = truth_ned(t)
        if case == "position":
            ap.position(boot_ms, north, east)
        elif case == "odometry":
            ap.odometry(boot_ms, north, east)
        elif case == "hostile":
            hostile(ap, t, boot_ms)
    out, err = child.communicate()
    if child.returncode != 0:
        fail(f"plumbline failed: {err}")
    s = json.loads(out.strip().splitlines()[-1])
    scans = s["scans"]
    if len(odometry) != scans or scans != int(seconds * RATE_HZ):
        fail(f"{scans} revolutions, {len(odometry)} ODOMETRY received")
    counts = {k: s[k] for k in ("motion_guesses", "estimate_missing", "estimate_stale",
                                "estimate_invalid", "estimate_discontinuities")}
    # The companion's map starts at the first revolution's pose; its ODOMETRY is FRD-flipped,
    # so sliding left shows as y going negative.
    last = odometry[-1]
    travelled = SPEED_M_S * (scans - 1) / RATE_HZ
    print(f"companion_autopilot: {case}: {scans} revolutions, {counts}, "
          f"last pose x {last.x:.3f} y {last.y:.3f} (slid {travelled:.2f} m left)")
    if case in ("position", "odometry"):
        # The first revolution has no estimate yet, the second none before it.
        if counts["motion_guesses"] < scans - 3:
            fail(f"only {counts['motion_guesses']} of {scans} revolutions had a guess: {counts}")
        # From the third revolution on (the first has no estimate before it, the second may
        # not, when the autopilot's first answer comes after the companion's first look), every
        # revolution moves left, and the end is within a post spacing of the truth (the match
        # may still settle one post off where two fit about equally well).
        guessed = odometry[2:]
        steps = [b.y - a.y for a, b in zip(guessed, guessed[1:])]
        slid = guessed[0].y - last.y
        expected = SPEED_M_S * (len(guessed) - 1) / RATE_HZ
        if max(steps) >= 0.0 or abs(slid - expected) > 1.5 * PERIOD_M or abs(last.x) > 0.1:
            fail(f"the pose did not follow the guessed motion: slid {slid:.2f} m, expected "
                 f"{expected:.2f} m; x {last.x}; steps {steps}")
    elif case == "silent":
        if counts["motion_guesses"] != 0 or counts["estimate_missing"] != scans:
            fail(f"guesses with no autopilot: {counts}")
        # Without a guess the match settles on the nearer look-alike: backwards.
        if last.y < 1.0:
            fail(f"the corridor is ambiguous without a guess, yet the pose slid to {last.y}")
        if "no revolution got a motion guess" not in err:
            fail(f"no warning about the missing estimate: {err}")
    elif case == "hostile":
        if counts["estimate_stale"] < 5 or counts["estimate_invalid"] < 5:
            fail(f"silence and bad estimates not counted: {counts}")
        if counts["estimate_discontinuities"] < 1:
            fail(f"the reboot went unnoticed: {counts}")
        if counts["motion_guesses"] < 12:
            fail(f"too few guesses around the faults: {counts}")
        withheld = sum(v for k, v in counts.items() if k != "motion_guesses")
        if counts["motion_guesses"] + withheld > scans:
            fail(f"a revolution both guessed and withheld: {counts}")
        if not all(math.isfinite(v) for m in odometry for v in (m.x, m.y)):
            fail("a non-finite pose went out")
    else:
        fail(f"unknown case {case}")


if __name__ == "__main__":
    main()
