#!/usr/bin/env python3
"""pymavlink in the autopilot's place: receives what `plumbline companion` sends while it replays
a lidar capture, and checks every message the way PX4 and ArduPilot read them.

usage: companion_client.py PLUMBLINE_BINARY CAPTURE
Exits non-zero, saying what was wrong, on the first failed check.
"""
import json
import math
import socket
import subprocess
import sys
import time

from pymavlink.dialects.v20 import common as mavlink
from peer_socket import loopback_socket


def fail(why):
    print(f"companion_client: {why}", file=sys.stderr)
    sys.exit(1)


def main():
    binary, capture = sys.argv[1], sys.argv[2]
    # Datagrams are collected as they come and decoded afterwards, so the peer keeps up with a
    # replay that runs as fast as it decodes (the companion drops what a full socket refuses).
    sock, port = loopback_socket(0.2)
    child = subprocess.Popen(
        [binary, "companion", "--lidar", "xv11", "--replay", capture,
         "--mavlink", f"udpout:127.0.0.1:{port}", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    datagrams = []
    quiet_since = None
    while True:
        try:
            datagrams.append(sock.recv(4096))
            quiet_since = None
        except socket.timeout:
            if child.poll() is None:
                continue
            quiet_since = quiet_since or time.monotonic()
            if time.monotonic() - quiet_since > 0.6:
                break
    parser = mavlink.MAVLink(None)
    got = {"HEARTBEAT": [], "ODOMETRY": [], "OBSTACLE_DISTANCE": [], "other": []}
    for d in datagrams:
        msgs = parser.parse_buffer(d) or []
        if len(msgs) != 1:
            fail(f"a datagram is not one MAVLink frame: {d.hex()}")
        kind = msgs[0].get_type()
        if kind == "BAD_DATA":
            fail(f"undecodable bytes: {msgs[0]}")
        got.get(kind, got["other"]).append(msgs[0])
    out, err = child.communicate()
    if child.returncode != 0:
        fail(f"plumbline failed: {err}")
    summary = json.loads(out.strip().splitlines()[-1])
    scans = summary["scans"]

    if got["other"]:
        fail(f"unexpected messages: {[m.get_type() for m in got['other']]}")
    odo, obs, beats = got["ODOMETRY"], got["OBSTACLE_DISTANCE"], got["HEARTBEAT"]
    if len(odo) != scans or len(obs) != scans:
        fail(f"{scans} revolutions but {len(odo)} ODOMETRY, {len(obs)} OBSTACLE_DISTANCE")

    for m in beats:
        if m.type != mavlink.MAV_TYPE_ONBOARD_CONTROLLER:
            fail(f"HEARTBEAT type {m.type}, not MAV_TYPE_ONBOARD_CONTROLLER")
        if m.autopilot != mavlink.MAV_AUTOPILOT_INVALID:
            fail(f"HEARTBEAT autopilot {m.autopilot}: a companion is not an autopilot")
    span_s = (odo[-1].time_usec - odo[0].time_usec) * 1e-6
    if abs(len(beats) - span_s) > 1.5:
        fail(f"{len(beats)} heartbeats over {span_s:.1f} s: not 1 Hz")

    lost = 0
    last_reset = odo[0].reset_counter
    for m in odo:
        if m.frame_id != mavlink.MAV_FRAME_LOCAL_FRD or m.child_frame_id != mavlink.MAV_FRAME_BODY_FRD:
            fail(f"frames {m.frame_id}/{m.child_frame_id}: ArduPilot accepts LOCAL_FRD/BODY_FRD only")
        if m.estimator_type != mavlink.MAV_ESTIMATOR_TYPE_VISION:
            fail(f"estimator_type {m.estimator_type}: PX4 takes VISION, not LIDAR")
        if not -1 <= m.quality <= 100:
            fail(f"quality {m.quality} outside -1..100")
        lost += m.quality == -1
        if abs(sum(v * v for v in m.q) - 1.0) > 1e-5:
            fail(f"quaternion {m.q} is not a unit quaternion")
        cov = m.pose_covariance
        # Upper triangle, row by row: x-x 0, y-y 6, z-z 11, roll 15, pitch 18, yaw 20.
        xy_yaw = [cov[i] for i in (0, 1, 5, 6, 10, 20)]
        if len(cov) != 21 or not all(math.isfinite(v) for v in xy_yaw):
            fail(f"pose covariance {cov}")
        if min(cov[0], cov[6], cov[20]) <= 0.0:
            fail(f"x, y or yaw variance not positive: {cov}")
        # PX4 drops a position with any NaN in it, ArduPilot pools the three variances of
        # position and of attitude: the unmeasured height, roll and pitch go out finite, with
        # the horizontal / yaw variance.
        if not math.isfinite(m.z) or not all(math.isfinite(cov[i]) for i in (11, 15, 18)):
            fail(f"a NaN in the pose: z {m.z}, {cov}")
        if cov[11] != max(cov[0], cov[6]) or cov[15] != cov[20] or cov[18] != cov[20]:
            fail(f"height, roll or pitch claimed better measured than x, y, yaw: {cov}")
        if m.quality == -1 and cov[0] < 100.0:
            fail(f"a lost pose claims {cov[0]} m^2")
        if not math.isnan(m.velocity_covariance[0]):
            fail("velocity covariance should be unknown (NaN first element)")
        if m.reset_counter < last_reset:
            fail(f"reset_counter went back: {last_reset} -> {m.reset_counter}")
        last_reset = m.reset_counter
    if lost != summary["lost_scans"]:
        fail(f"{lost} ODOMETRY with quality -1, summary says {summary['lost_scans']} lost")
    if last_reset != summary["reset_counter"]:
        fail(f"last reset_counter {last_reset}, summary says {summary['reset_counter']}")

    for m in obs:
        if m.frame != mavlink.MAV_FRAME_BODY_FRD:
            fail(f"OBSTACLE_DISTANCE frame {m.frame}, not BODY_FRD")
        if len(m.distances) != 72 or m.increment_f != 5.0 or m.angle_offset != 0.0:
            fail(f"OBSTACLE_DISTANCE layout: {len(m.distances)} sectors of {m.increment_f} deg")
        known = [d for d in m.distances if d != 65535]
        # max_distance + 1 says "nothing in range" in that sector.
        if any(not m.min_distance <= d <= m.max_distance + 1 for d in known):
            fail(f"distances outside [{m.min_distance}, {m.max_distance} + 1] cm: {known}")
    if not any(d != 65535 for m in obs for d in m.distances):
        fail("no sector ever saw an obstacle")

    print(f"companion_client: ok: {scans} ODOMETRY ({lost} lost), {scans} OBSTACLE_DISTANCE, "
          f"{len(beats)} HEARTBEAT over {span_s:.1f} s, reset_counter {last_reset}")


if __name__ == "__main__":
    main()
